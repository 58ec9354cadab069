//! The server's integration tests: the API against a server on an ephemeral loopback port
//! (every endpoint, every error code, auth, all-or-nothing uploads), concurrency, and the
//! dashboard in a real headless Chromium.

mod api;
mod browser;
mod cache;
mod common;
mod concurrency;
mod defects;
mod farms;
mod hardening;
mod missions;
