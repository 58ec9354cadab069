//! Who a request is: its `Authorization` header checked against the server's [`Token`]
//! (or, on a farm, the farm token's scope), as the `Caller`/`Computing`/`Writing` extractors.

use axum::extract::FromRequestParts;
use axum::http::request::Parts;
use axum::http::{HeaderMap, header};

use crate::error::ApiError;
use crate::farms::{FarmAccess, Scope};
use crate::state::AppState;
pub use crate::token::{MIN_TOKEN_LEN, Token, TokenError};

/// Reads an `Authorization` header: `Ok(false)` when there is none, `Ok(true)` when it is
/// `Bearer <token>` with this server's token (the scheme in any case, RFC 7235; one or more
/// spaces before the token), 401 when it is anything else (another scheme, a wrong token) or
/// the server has no token to compare it with.
pub fn authenticate(token: Option<&Token>, headers: &HeaderMap) -> Result<bool, ApiError> {
    let Some(value) = headers.get(header::AUTHORIZATION) else {
        return Ok(false);
    };
    let bytes = value.as_bytes();
    let (scheme, rest) = match bytes.iter().position(|&b| b == b' ') {
        Some(i) => (&bytes[..i], &bytes[i..]),
        None => (bytes, &b""[..]),
    };
    if !scheme.eq_ignore_ascii_case(b"bearer") {
        return Err(ApiError::unauthorized(
            "expected Authorization: Bearer <token>",
        ));
    }
    let given = rest.trim_ascii();
    match token {
        Some(t) if t.matches(given) => Ok(true),
        Some(_) => Err(ApiError::unauthorized(
            "the bearer token is not this server's",
        )),
        None => Err(ApiError::forbidden(
            "this server was started without a token, so nothing needing one is possible",
        )),
    }
}

/// Checks a write request's `Authorization: Bearer <token>` header against `token`.
/// 403 when the server has no token (writes disabled), 401 when the header is missing,
/// malformed or wrong.
pub fn authorize(token: Option<&Token>, headers: &HeaderMap) -> Result<(), ApiError> {
    if token.is_none() {
        return Err(ApiError::forbidden(
            "this server was started without a token, so writes are disabled",
        ));
    }
    if authenticate(token, headers)? {
        Ok(())
    } else {
        Err(ApiError::unauthorized(
            "this request writes: send Authorization: Bearer <token>",
        ))
    }
}

/// Who sent a request, checked from its headers before its body is read: a wrong or
/// malformed `Authorization` is refused (401) whatever the route.
#[derive(Debug, Clone, Copy)]
pub struct Caller {
    /// Whether the request may write: it carries this server's token (or, on a farm, a farm
    /// token with the write scope).
    pub authenticated: bool,
    /// Whether it carries a farm token with the read scope only.
    pub read_scope: bool,
}

impl Caller {
    /// Refuses a caller without the token for work that writes: 403 on a server without a
    /// token or for a farm token of read scope, 401 otherwise.
    pub fn require_write(&self, state: &AppState) -> Result<(), ApiError> {
        if self.authenticated {
            return Ok(());
        }
        if self.read_scope || state.0.farm {
            return Err(ApiError::forbidden(
                "this farm token has the read scope: writes need a token with the write scope",
            ));
        }
        if state.0.token.is_none() {
            return Err(ApiError::forbidden(
                "this server was started without a token, so writes are disabled",
            ));
        }
        Err(ApiError::unauthorized(
            "this request writes: send Authorization: Bearer <token>",
        ))
    }
}

impl FromRequestParts<AppState> for Caller {
    type Rejection = ApiError;

    async fn from_request_parts(parts: &mut Parts, state: &AppState) -> Result<Self, ApiError> {
        if state.0.farm {
            // The dispatcher checked the farm token; without its word, nothing is allowed.
            let access = parts
                .extensions
                .get::<FarmAccess>()
                .ok_or_else(|| ApiError::unauthorized("send Authorization: Bearer <farm token>"))?;
            let write = access.scope == Scope::Write;
            return Ok(Self {
                authenticated: write,
                read_scope: !write,
            });
        }
        Ok(Self {
            authenticated: authenticate(state.0.token.as_ref(), &parts.headers)?,
            read_scope: false,
        })
    }
}

/// A caller allowed to run a computation (a preview, a dry run, a simulation, a
/// reconstruction): anyone on a loopback-only server, otherwise only with the token. Checked
/// before the body is read.
#[derive(Debug, Clone, Copy)]
pub struct Computing(pub Caller);

impl FromRequestParts<AppState> for Computing {
    type Rejection = ApiError;

    async fn from_request_parts(parts: &mut Parts, state: &AppState) -> Result<Self, ApiError> {
        let caller = Caller::from_request_parts(parts, state).await?;
        if !caller.authenticated && !state.0.open_compute {
            return Err(match state.0.token {
                None => ApiError::forbidden(
                    "this server was started without a token, so computations are disabled",
                ),
                Some(_) => ApiError::unauthorized(
                    "computations need the token on this server: send Authorization: Bearer <token>",
                ),
            });
        }
        Ok(Self(caller))
    }
}

/// A caller with the token: what every upload (ingest, record) needs. Checked before the
/// body is read.
#[derive(Debug, Clone, Copy)]
pub struct Writing;

impl FromRequestParts<AppState> for Writing {
    type Rejection = ApiError;

    async fn from_request_parts(parts: &mut Parts, state: &AppState) -> Result<Self, ApiError> {
        Caller::from_request_parts(parts, state)
            .await?
            .require_write(state)?;
        Ok(Self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn authorization_header_is_checked() {
        let t = Token::new("0123456789abcdef-token").unwrap();
        let mut h = HeaderMap::new();
        assert_eq!(authorize(Some(&t), &h).unwrap_err().status, 401);
        h.insert(header::AUTHORIZATION, "Basic abc".parse().unwrap());
        assert_eq!(authorize(Some(&t), &h).unwrap_err().status, 401);
        h.insert(
            header::AUTHORIZATION,
            "Bearer 0123456789abcdef-token".parse().unwrap(),
        );
        assert!(authorize(Some(&t), &h).is_ok());
        assert_eq!(authorize(None, &h).unwrap_err().status, 403);
        // RFC 7235: the scheme in any case; the token itself is exact.
        for ok in [
            "bearer 0123456789abcdef-token",
            "BEARER 0123456789abcdef-token",
            "Bearer   0123456789abcdef-token",
        ] {
            h.insert(header::AUTHORIZATION, ok.parse().unwrap());
            assert_eq!(authenticate(Some(&t), &h), Ok(true), "{ok}");
        }
        for bad in [
            "Bearer 0123456789ABCDEF-TOKEN",
            "Bearer",
            "Bearer0123456789abcdef-token",
            "Basic 0123456789abcdef-token",
        ] {
            h.insert(header::AUTHORIZATION, bad.parse().unwrap());
            assert_eq!(authenticate(Some(&t), &h).unwrap_err().status, 401, "{bad}");
        }
        assert_eq!(authenticate(Some(&t), &HeaderMap::new()), Ok(false));
    }
}
