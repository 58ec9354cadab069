//! The bearer token that guards every write: read from an environment variable or a file,
//! compared in constant time, never printed by `Debug` and never logged.

use std::fmt;
use std::path::Path;

use axum::extract::FromRequestParts;
use axum::http::request::Parts;
use axum::http::{HeaderMap, header};
use subtle::ConstantTimeEq;

use crate::error::ApiError;
use crate::state::AppState;

/// Shortest token accepted, bytes: guessing one is out of reach over a network.
pub const MIN_TOKEN_LEN: usize = 16;

/// A write token. `Debug` shows `Token(****)`; the only way to read it back is
/// [`Token::reveal`], for the one line that hands it to the operator.
#[derive(Clone)]
pub struct Token(Vec<u8>);

impl fmt::Debug for Token {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("Token(****)")
    }
}

/// Why a token was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum TokenError {
    /// Shorter than [`MIN_TOKEN_LEN`] (the length, never the token, is reported).
    #[error("the token has {0} characters: at least {MIN_TOKEN_LEN} are needed")]
    TooShort(usize),
    /// Contains whitespace or control characters, which an HTTP header cannot carry.
    #[error("the token contains whitespace or control characters")]
    BadCharacters,
    /// The token file could not be read.
    #[error("{path}: cannot read the token file: {reason}")]
    File {
        /// The file.
        path: String,
        /// The OS message.
        reason: String,
    },
    /// The system's random source failed.
    #[error("cannot draw a random token: {0}")]
    Random(String),
}

impl Token {
    /// A token from its text (surrounding whitespace removed).
    pub fn new(text: &str) -> Result<Self, TokenError> {
        let t = text.trim();
        if t.len() < MIN_TOKEN_LEN {
            return Err(TokenError::TooShort(t.len()));
        }
        if t.chars().any(|c| c.is_whitespace() || c.is_control()) {
            return Err(TokenError::BadCharacters);
        }
        Ok(Self(t.as_bytes().to_vec()))
    }

    /// The token stored in `path` (its first line; a trailing newline is ignored).
    pub fn from_file(path: &Path) -> Result<Self, TokenError> {
        let text = std::fs::read_to_string(path).map_err(|e| TokenError::File {
            path: path.display().to_string(),
            reason: e.to_string(),
        })?;
        Self::new(text.lines().next().unwrap_or(""))
    }

    /// 32 random bytes from the operating system, as 64 hex digits.
    pub fn random() -> Result<Self, TokenError> {
        let mut bytes = [0u8; 32];
        getrandom::fill(&mut bytes).map_err(|e| TokenError::Random(e.to_string()))?;
        let hex: String = bytes.iter().map(|b| format!("{b:02x}")).collect();
        Self::new(&hex)
    }

    /// The token's text, for handing it to the operator once (never for logs).
    pub fn reveal(&self) -> &str {
        std::str::from_utf8(&self.0).unwrap_or("")
    }

    /// Whether `candidate` is this token, in time independent of where they differ.
    pub fn matches(&self, candidate: &[u8]) -> bool {
        // Lengths are compared in constant time too, as a choice (a length leak alone would
        // not reveal a random token, but there is no reason to give it).
        let len_ok = (self.0.len() as u64).ct_eq(&(candidate.len() as u64));
        let n = self.0.len().min(candidate.len());
        let bytes_ok = self.0[..n].ct_eq(&candidate[..n]);
        (len_ok & bytes_ok).into()
    }
}

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
                .get::<crate::farms::FarmAccess>()
                .ok_or_else(|| ApiError::unauthorized("send Authorization: Bearer <farm token>"))?;
            let write = access.scope == crate::farms::Scope::Write;
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
    fn tokens_match_only_themselves_and_never_print() {
        let t = Token::new("0123456789abcdef-token").unwrap();
        assert!(t.matches(b"0123456789abcdef-token"));
        assert!(!t.matches(b"0123456789abcdef-tokem"));
        assert!(!t.matches(b"0123456789abcdef-toke"));
        assert!(!t.matches(b"0123456789abcdef-token2"));
        assert!(!t.matches(b""));
        assert_eq!(format!("{t:?}"), "Token(****)");
        assert!(matches!(Token::new("short"), Err(TokenError::TooShort(5))));
        assert!(matches!(
            Token::new("0123456789 abcdef"),
            Err(TokenError::BadCharacters)
        ));
        let r = Token::random().unwrap();
        assert_eq!(r.reveal().len(), 64);
        assert_ne!(r.reveal(), Token::random().unwrap().reveal());
    }

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
