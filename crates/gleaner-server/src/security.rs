//! Middleware every request passes: the `Host` allow-list (DNS rebinding), the security
//! headers on every response, the request log (paths and redacted queries, never a header or
//! a query value that could be a secret), and the JSON 405.

use std::net::IpAddr;
use std::sync::Arc;

use axum::extract::Request;
use axum::http::{HeaderMap, HeaderName, HeaderValue, Method, header};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use tower_http::classify::{ServerErrorsAsFailures, SharedClassifier};
use tower_http::trace::TraceLayer;

use crate::error::ApiError;

/// The policy of the API's responses (the dashboard's pages set their own, stricter one for
/// what a page may load): nothing may be loaded, framed or run from them.
pub const API_CSP: &str =
    "default-src 'none'; frame-ancestors 'none'; base-uri 'none'; form-action 'none'";

/// The host names the server answers to.
#[derive(Debug, Clone)]
pub struct Hosts(Vec<String>);

impl Hosts {
    /// `localhost`, IP literals and the configured names.
    pub fn new(allowed: &[String]) -> Self {
        Self(allowed.iter().map(|h| h.to_ascii_lowercase()).collect())
    }

    /// Whether a `Host` header value (`name[:port]`, `[v6]:port`) names this server.
    pub fn allows(&self, host: &str) -> bool {
        let name = match host.strip_prefix('[') {
            // An IPv6 literal: `[::1]` or `[::1]:8080`.
            Some(rest) => {
                let Some((addr, port)) = rest.split_once(']') else {
                    return false;
                };
                let port_ok = port.is_empty()
                    || port
                        .strip_prefix(':')
                        .is_some_and(|p| !p.is_empty() && p.bytes().all(|b| b.is_ascii_digit()));
                return port_ok && addr.parse::<std::net::Ipv6Addr>().is_ok();
            }
            None => match host.rsplit_once(':') {
                Some((name, port))
                    if !port.is_empty() && port.bytes().all(|b| b.is_ascii_digit()) =>
                {
                    name
                }
                Some(_) => return false,
                None => host,
            },
        };
        let name = name.strip_suffix('.').unwrap_or(name).to_ascii_lowercase();
        // A name resolved by DNS can point anywhere; an address literal cannot be rebound.
        name.parse::<IpAddr>().is_ok()
            || name == "localhost"
            || name.ends_with(".localhost")
            || self.0.contains(&name)
    }
}

/// Refuses a request whose `Host` is missing or not this server's (421), before anything
/// else: a page on another site that rebinds its name to this address reads nothing.
pub async fn check_host(hosts: Arc<Hosts>, req: Request, next: Next) -> Response {
    let host = req
        .headers()
        .get(header::HOST)
        .and_then(|h| h.to_str().ok())
        .map(str::to_string)
        .or_else(|| req.uri().authority().map(|a| a.as_str().to_string()));
    match host {
        None => ApiError::bad_request(Some("Host"), "the request has no Host header").into_response(),
        Some(h) if !hosts.allows(&h) => ApiError::misdirected(format!(
            "this server does not answer to the host {h:?}: use localhost, an IP address, or start it with --allow-host {}",
            h.rsplit_once(':').map_or(h.as_str(), |(n, _)| n)
        ))
        .into_response(),
        Some(_) => next.run(req).await,
    }
}

/// Refuses (401) a request whose `Authorization` is present but not this server's token, on
/// every route (a read does not need one, but a wrong one is never ignored).
pub async fn refuse_wrong_tokens(
    token: Arc<Option<crate::Token>>,
    req: Request,
    next: Next,
) -> Response {
    if token.is_some()
        && req.headers().contains_key(header::AUTHORIZATION)
        && let Err(e) = crate::auth::authenticate(token.as_ref().as_ref(), req.headers())
    {
        return e.into_response();
    }
    next.run(req).await
}

/// Adds `X-Content-Type-Options: nosniff`, a Content-Security-Policy (unless the response
/// set its own), `Referrer-Policy: no-referrer` and `X-Frame-Options: DENY` to every response.
pub async fn headers(req: Request, next: Next) -> Response {
    let mut r = next.run(req).await;
    let h = r.headers_mut();
    set_static(h, NOSNIFF);
    if !h.contains_key(header::CONTENT_SECURITY_POLICY) {
        h.insert(
            header::CONTENT_SECURITY_POLICY,
            HeaderValue::from_static(API_CSP),
        );
    }
    set_static(h, NO_REFERRER);
    set_static(h, ("x-frame-options", "DENY"));
    r
}

/// `X-Content-Type-Options: nosniff`: a response is read as its declared type only.
pub(crate) const NOSNIFF: (&str, &str) = ("x-content-type-options", "nosniff");

/// `Referrer-Policy: no-referrer`: no page of this server is named to another.
pub(crate) const NO_REFERRER: (&str, &str) = ("referrer-policy", "no-referrer");

/// Sets the header `name: value` (lowercase name), replacing any value it had.
pub(crate) fn set_static(h: &mut HeaderMap, (name, value): (&'static str, &'static str)) {
    h.insert(
        HeaderName::from_static(name),
        HeaderValue::from_static(value),
    );
}

/// 405 with the JSON error body (axum keeps its `Allow` header).
pub async fn method_not_allowed(method: Method) -> Response {
    ApiError::method_not_allowed(format!(
        "{method} is not allowed here (see /api/v1/openapi.json for each path's methods)"
    ))
    .into_response()
}

/// Query parameters the API defines, logged with their values; any other parameter is logged
/// by name only, so a token put in a query string never reaches the log.
const LOGGED_PARAMETERS: [&str; 10] = [
    "at",
    "modality",
    "neighbours",
    "estimator",
    "days",
    "mission",
    "from",
    "to",
    "every_hours",
    "cell",
];

/// A query string with the value of every parameter the API does not define replaced by `…`.
pub fn redact_query(query: &str) -> String {
    query
        .split('&')
        .map(|pair| {
            let (name, value) = pair.split_once('=').unwrap_or((pair, ""));
            if LOGGED_PARAMETERS.contains(&name) {
                format!("{name}={value}")
            } else if value.is_empty() {
                name.chars().take(64).collect()
            } else {
                format!("{}=…", name.chars().take(64).collect::<String>())
            }
        })
        .collect::<Vec<_>>()
        .join("&")
}

/// The request log: one span per request with the method, the path and the redacted query
/// (never the headers: the `Authorization` token is not logged).
pub fn trace_layer()
-> TraceLayer<SharedClassifier<ServerErrorsAsFailures>, impl Fn(&Request) -> tracing::Span + Clone>
{
    TraceLayer::new_for_http().make_span_with(|req: &Request| {
        let query = req.uri().query().map(redact_query).unwrap_or_default();
        tracing::debug_span!(
            "request",
            method = %req.method(),
            path = %req.uri().path(),
            query = %query,
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hosts_are_localhost_literals_or_configured_names() {
        let h = Hosts::new(&["Farm.Example".to_string()]);
        for ok in [
            "localhost",
            "localhost:8080",
            "LOCALHOST.:1",
            "127.0.0.1:8080",
            "10.1.2.3",
            "[::1]:8080",
            "[::1]",
            "farm.example",
            "farm.example:443",
            "app.localhost:3000",
        ] {
            assert!(h.allows(ok), "{ok}");
        }
        for bad in [
            "evil.example",
            "evil.example:8080",
            "127.0.0.1.evil.example",
            "farm.example.evil",
            "[::1",
            "[::1]x",
            "localhost:",
            "localhost:80a",
            "",
            "[evil]:80",
        ] {
            assert!(!h.allows(bad), "{bad}");
        }
    }

    #[test]
    fn only_api_parameters_keep_their_values_in_the_log() {
        assert_eq!(
            redact_query("at=2014-03-01&token=s3cret&access_token=x&days=3&flag"),
            "at=2014-03-01&token=…&access_token=…&days=3&flag"
        );
        assert!(!redact_query("Authorization=Bearer%20abc").contains("abc"));
    }
}
