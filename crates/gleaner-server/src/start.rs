//! `gleaner serve`'s start-up, for any front end: the write token it runs with, glibc's
//! malloc settings, the log, the runtime and the listener, serving until ctrl-c or SIGTERM;
//! and `gleaner farm-token`'s new farm token.

use std::ffi::OsString;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use crate::{Farms, Scope, ServerConfig, ServerError, Token};

/// glibc's malloc settings the server runs with unless its environment sets `GLIBC_TUNABLES`
/// itself: blocks of 128 KiB or more in mappings of their own, returned when freed, and a
/// heap trimmed when more than 128 KiB is free at its top. With glibc's defaults the mmap
/// threshold rises to the largest block freed so far (up to 32 MB), so a simulation's large
/// buffers come back from the arenas and stay there: the resident memory grew by 40% over
/// repeated simulations with 2.6 MB live (BENCHMARKS.md, "Server memory over repeated
/// simulations").
pub const MALLOC_TUNABLES: &str =
    "glibc.malloc.mmap_threshold=131072:glibc.malloc.trim_threshold=131072";

/// Re-executes this binary, same arguments and process, with [`MALLOC_TUNABLES`] (glibc
/// reads them only at start-up) unless `GLIBC_TUNABLES` is already set; returns only when
/// that cannot be done (or off glibc), and the server then runs with the defaults.
pub fn with_malloc_tunables() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        use std::os::unix::process::CommandExt as _;
        if std::env::var_os("GLIBC_TUNABLES").is_some() {
            return;
        }
        let Ok(exe) = std::env::current_exe() else {
            return;
        };
        let err = std::process::Command::new(exe)
            .args(std::env::args_os().skip(1))
            .env("GLIBC_TUNABLES", MALLOC_TUNABLES)
            .exec();
        eprintln!(
            "gleaner serve: running with glibc's malloc defaults (re-executing failed: {err})"
        );
    }
}

/// Where the write token of a single-project server comes from.
#[derive(Debug, Default)]
pub struct TokenSource<'a> {
    /// Serve read-only: no token.
    pub read_only: bool,
    /// A file holding the token (first line).
    pub file: Option<&'a Path>,
    /// The `GLEANER_TOKEN` environment variable's value.
    pub env: Option<OsString>,
}

/// The write token `config` runs with, and whether it was drawn here: none for a farms server
/// (farm tokens only) or read-only; else the file's, else the environment's, else on
/// loopback a random one; else none ([`ServerConfig::check`] then refuses the address).
pub fn write_token(
    config: &ServerConfig,
    source: TokenSource<'_>,
) -> Result<(Option<Token>, bool), ServerError> {
    let bad = |e: crate::TokenError| ServerError::Config(e.to_string());
    if config.farms.is_some() || source.read_only {
        Ok((None, false))
    } else if let Some(path) = source.file {
        Ok((Some(Token::from_file(path).map_err(bad)?), false))
    } else if let Some(t) = source.env {
        let t = t
            .into_string()
            .map_err(|_| ServerError::Config("GLEANER_TOKEN is not valid UTF-8".into()))?;
        let token =
            Token::new(&t).map_err(|e| ServerError::Config(format!("GLEANER_TOKEN: {e}")))?;
        Ok((Some(token), false))
    } else if config.addr.ip().is_loopback() {
        Ok((Some(Token::random().map_err(bad)?), true))
    } else {
        Ok((None, false))
    }
}

/// Serves `config` until ctrl-c or SIGTERM on a runtime of its own, the request log on
/// standard error (`GLEANER_LOG` filters it); prints the dashboard's address ([`crate::announce`],
/// with a token `generated` here) or the farms, then `stopped`.
pub fn serve_until_stopped(config: ServerConfig, generated: bool) -> Result<(), ServerError> {
    config.check()?;
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_env("GLEANER_LOG")
                .unwrap_or_else(|_| "info,tower_http=debug".into()),
        )
        .with_writer(std::io::stderr)
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .init();
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .map_err(|e| ServerError::Config(format!("starting the async runtime: {e}")))?;
    runtime.block_on(async move {
        let listener = tokio::net::TcpListener::bind(config.addr)
            .await
            .map_err(|e| ServerError::Config(format!("cannot listen on {}: {e}", config.addr)))?;
        let addr = listener.local_addr()?;
        if config.farms.is_some() {
            let farms = Farms::open(&config)?;
            println!(
                "farms: {}\nAPI: http://{addr}/api/v1/farms/{{farm}}/ (a farm token in Authorization: Bearer) · http://{addr}/api/v1/openapi.json · stop with ctrl-c",
                farms.names().join(", ")
            );
            crate::serve_farms(listener, &config, farms, shutdown_signal()).await?;
        } else {
            let terminal = std::io::IsTerminal::is_terminal(&std::io::stdout());
            let token = config.token.as_ref();
            println!("{}", crate::announce(addr, token, generated, terminal));
            crate::serve(listener, &config, shutdown_signal()).await?;
        }
        println!("stopped");
        Ok(())
    })
}

/// Completes on ctrl-c (SIGINT) or, on Unix, SIGTERM (a service manager's stop).
pub async fn shutdown_signal() {
    #[cfg(unix)]
    {
        use tokio::signal::unix::{SignalKind, signal};
        match signal(SignalKind::terminate()) {
            Ok(mut term) => {
                tokio::select! {
                    _ = tokio::signal::ctrl_c() => {}
                    _ = term.recv() => {}
                }
            }
            Err(_) => {
                tokio::signal::ctrl_c().await.ok();
            }
        }
    }
    #[cfg(not(unix))]
    tokio::signal::ctrl_c().await.ok();
}

/// Draws a token for `farm` (a farm of the directory `farms`) with `scope` and appends its
/// SHA-256 to the tokens file (`tokens`, else `farms/tokens`); returns the token, to be shown
/// once, and the file. A running server reads the file at start-up.
pub fn add_farm_token(
    farms: &Path,
    farm: &str,
    scope: Scope,
    tokens: Option<PathBuf>,
) -> Result<(Token, PathBuf), ServerError> {
    let dirs = crate::farms::farm_dirs(farms)?;
    if !dirs.contains_key(farm) {
        return Err(ServerError::Config(format!(
            "{}: no farm {farm:?} in it (farms: {})",
            farms.display(),
            dirs.keys().cloned().collect::<Vec<_>>().join(", ")
        )));
    }
    let path = tokens.unwrap_or_else(|| farms.join("tokens"));
    let (token, line) = crate::farms::new_token_line(farm, scope)?;
    let cannot = |what: &str, e: std::io::Error| {
        ServerError::Config(format!("{}: cannot {what}: {e}", path.display()))
    };
    let mut file = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&path)
        .map_err(|e| cannot("open the tokens file", e))?;
    writeln!(file, "{line}").map_err(|e| cannot("write", e))?;
    Ok((token, path))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_loopback_server_draws_a_token_and_a_read_only_one_has_none() {
        let config = ServerConfig::new(PathBuf::from("."));
        let (token, generated) = write_token(&config, TokenSource::default()).unwrap();
        assert!(token.is_some() && generated);
        let read_only = TokenSource {
            read_only: true,
            ..Default::default()
        };
        let (token, generated) = write_token(&config, read_only).unwrap();
        assert!(token.is_none() && !generated);
        let env = TokenSource {
            env: Some("x".repeat(40).into()),
            ..Default::default()
        };
        let (token, generated) = write_token(&config, env).unwrap();
        assert!(token.is_some() && !generated);
    }

    #[test]
    fn a_farm_token_for_an_unknown_farm_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(dir.path().join("north")).unwrap();
        std::fs::write(dir.path().join("north").join("gleaner.toml"), "").unwrap();
        let err = add_farm_token(dir.path(), "east", Scope::Read, None).unwrap_err();
        assert!(err.to_string().contains("(farms: north)"), "{err}");
        let (token, path) = add_farm_token(dir.path(), "north", Scope::Write, None).unwrap();
        let file = std::fs::read_to_string(path).unwrap();
        assert!(file.starts_with("north write ") && !file.contains(token.reveal()));
    }
}
