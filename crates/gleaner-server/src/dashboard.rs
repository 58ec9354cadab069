//! The dashboard: one HTML page, its stylesheet and its script, written for gleaner and
//! embedded in the binary (`include_str!`), so `cargo build` alone gives a server with the
//! whole dashboard and the page needs no network. The map itself is the SVG the CLI's export
//! draws (`/api/v1/map.svg`), made interactive by the script.
//!
//! Every asset is served with a Content-Security-Policy that allows only this server (and
//! the configured basemap's origin for images), so the page cannot load or send anything
//! elsewhere.
//!
//! A farms server (`gleaner serve --farms DIR`) serves the same page marked
//! `<body data-farms>`: the script then shows a farm picker, asks `GET /api/v1/farms` which
//! farm each farm token given to the page opens, and talks to the chosen farm's routes
//! (`/api/v1/farms/{farm}/...`) with that farm's token.

use axum::Router;
use axum::body::Bytes;
use axum::http::{HeaderValue, header};
use axum::response::{IntoResponse, Response};
use axum::routing::get;

use crate::security;

/// The page.
pub const INDEX_HTML: &str = include_str!("../assets/index.html");
/// Its script.
pub const APP_JS: &str = include_str!("../assets/app.js");
/// Its stylesheet.
pub const APP_CSS: &str = include_str!("../assets/app.css");
/// Its icon: a cell square with a route through it.
pub const FAVICON_SVG: &str = include_str!("../assets/favicon.svg");

/// The origin (`scheme://host[:port]`) of a basemap URL template.
fn origin(url: &str) -> Option<&str> {
    let rest = url.split_once("://")?.1;
    let host_len = rest.find('/').unwrap_or(rest.len());
    Some(&url[..url.len() - rest.len() + host_len])
}

/// The page as a farms server serves it: `<body data-farms>`, which makes the script show the
/// farm picker and use the farms' routes.
pub fn farms_index_html() -> String {
    INDEX_HTML.replacen("<body>", "<body data-farms>", 1)
}

fn asset(body: Bytes, media: &'static str, csp: &HeaderValue) -> Response {
    let mut r = body.into_response();
    let h = r.headers_mut();
    h.insert(header::CONTENT_TYPE, HeaderValue::from_static(media));
    h.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-cache"));
    security::set_static(h, security::NOSNIFF);
    security::set_static(h, security::NO_REFERRER);
    h.insert(header::CONTENT_SECURITY_POLICY, csp.clone());
    r
}

/// The dashboard's routes: `/`, `/app.js`, `/app.css`, `/favicon.svg` (and `/favicon.ico`,
/// 204); with `farms`, the page of a farms server ([`farms_index_html`]).
pub fn routes<S: Clone + Send + Sync + 'static>(
    basemap_url: Option<&str>,
    farms: bool,
) -> Router<S> {
    let img = match basemap_url.and_then(origin) {
        Some(o) => format!("'self' data: blob: {o}"),
        None => "'self' data: blob:".to_string(),
    };
    let csp = HeaderValue::from_str(&format!(
        "default-src 'self'; img-src {img}; style-src 'self' 'unsafe-inline'; script-src 'self'; connect-src 'self'; frame-ancestors 'none'; base-uri 'none'; form-action 'self'"
    ))
    .unwrap_or_else(|_| HeaderValue::from_static("default-src 'self'"));
    let (c1, c2, c3, c4) = (csp.clone(), csp.clone(), csp.clone(), csp);
    let index = match farms {
        true => Bytes::from(farms_index_html()),
        false => Bytes::from_static(INDEX_HTML.as_bytes()),
    };
    let page = |body: Bytes, media: &'static str, csp: HeaderValue| {
        get(move || async move { asset(body, media, &csp) })
    };
    Router::new()
        .route("/", page(index, "text/html; charset=utf-8", c1))
        .route(
            "/app.js",
            page(
                Bytes::from_static(APP_JS.as_bytes()),
                "text/javascript; charset=utf-8",
                c2,
            ),
        )
        .route(
            "/app.css",
            page(
                Bytes::from_static(APP_CSS.as_bytes()),
                "text/css; charset=utf-8",
                c3,
            ),
        )
        .route(
            "/favicon.svg",
            page(
                Bytes::from_static(FAVICON_SVG.as_bytes()),
                "image/svg+xml",
                c4,
            ),
        )
        // Browsers ask for it whatever the page says: nothing to show, and no 404 in the log.
        .route(
            "/favicon.ico",
            get(|| async { axum::http::StatusCode::NO_CONTENT }),
        )
}

#[cfg(test)]
mod tests {
    #[test]
    fn basemap_origin() {
        assert_eq!(
            super::origin("https://tiles.example/a/{z}/{x}/{y}.png"),
            Some("https://tiles.example")
        );
        assert_eq!(super::origin("http://h:8000"), Some("http://h:8000"));
    }

    #[test]
    fn the_farms_page_is_marked() {
        let page = super::farms_index_html();
        assert_eq!(page.matches("<body data-farms>").count(), 1);
        assert!(!super::INDEX_HTML.contains("data-farms>"));
    }

    #[test]
    fn the_page_loads_nothing_from_elsewhere() {
        for text in [
            super::INDEX_HTML,
            super::APP_JS,
            super::APP_CSS,
            super::FAVICON_SVG,
        ] {
            // The only absolute URL is the SVG namespace (a name, never fetched).
            let rest = text.replace("http://www.w3.org/2000/svg", "");
            assert!(
                !rest.contains("http://") && !rest.contains("https://") && !rest.contains("//cdn")
            );
        }
    }
}
