//! `gleaner serve`: parses the flags and runs the HTTP API and dashboard
//! (`gleaner-server`) until ctrl-c.

use std::net::SocketAddr;
use std::path::PathBuf;

use anyhow::{Context, Result};
use gleaner_server::{ServerConfig, Token};

// The arguments of `gleaner serve` (no doc comment: the variant's is the help).
#[derive(clap::Args)]
pub struct ServeArgs {
    /// Project directory.
    #[arg(long, value_name = "PROJECT", default_value = ".")]
    project: PathBuf,
    /// Address to listen on; anything but loopback needs a token.
    #[arg(long, default_value = gleaner_server::DEFAULT_ADDR)]
    addr: SocketAddr,
    /// File holding the write token (first line) [default: the GLEANER_TOKEN environment
    /// variable; on loopback without either, a random token printed once at start-up].
    #[arg(long)]
    token_file: Option<PathBuf>,
    /// Serve read-only: no token, every write refused (loopback only).
    #[arg(long, conflicts_with = "token_file")]
    read_only: bool,
    /// Allow cross-origin requests from this origin (repeatable), e.g. http://localhost:3000
    /// [default: none, CORS off].
    #[arg(long = "cors-origin", value_name = "ORIGIN")]
    cors_origins: Vec<String>,
    /// Another host name the server answers to (repeatable), e.g. its name behind a reverse
    /// proxy [default: localhost and IP addresses only; other names are refused, against
    /// DNS rebinding].
    #[arg(long = "allow-host", value_name = "NAME")]
    allowed_hosts: Vec<String>,
    /// Basemap tile URL template drawn under the cells, e.g.
    /// https://tile.example/{z}/{x}/{y}.png [default: none; the dashboard needs no network].
    #[arg(long)]
    basemap_url: Option<String>,
    /// Largest upload, MiB.
    #[arg(long, default_value_t = 64)]
    max_upload_mib: usize,
    /// Longest planner time limit a request may ask for, s.
    #[arg(long, default_value_t = 60.0)]
    max_time_limit: f64,
}

/// Runs the server until ctrl-c or SIGTERM; prints the dashboard's address (with the token in the URL's
/// fragment when the token was generated here, so it never reaches a log).
pub fn run(args: ServeArgs) -> Result<()> {
    let mut generated = false;
    let token = if args.read_only {
        None
    } else if let Some(path) = &args.token_file {
        Some(Token::from_file(path)?)
    } else if let Some(t) = std::env::var_os("GLEANER_TOKEN") {
        let t = t
            .into_string()
            .map_err(|_| anyhow::anyhow!("GLEANER_TOKEN is not valid UTF-8"))?;
        Some(Token::new(&t).context("GLEANER_TOKEN")?)
    } else if args.addr.ip().is_loopback() {
        generated = true;
        Some(Token::random()?)
    } else {
        None
    };
    let config = ServerConfig {
        project: args.project,
        addr: args.addr,
        token,
        cors_origins: args.cors_origins,
        allowed_hosts: args.allowed_hosts,
        basemap_url: args.basemap_url,
        max_upload_bytes: args.max_upload_mib.saturating_mul(1 << 20),
        max_time_limit_s: args.max_time_limit,
        ..ServerConfig::new(PathBuf::new())
    };
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
        .context("starting the async runtime")?;
    runtime.block_on(async move {
        let listener = tokio::net::TcpListener::bind(config.addr)
            .await
            .with_context(|| format!("cannot listen on {}", config.addr))?;
        let addr = listener.local_addr()?;
        println!(
            "{}",
            gleaner_server::announce(
                addr,
                config.token.as_ref(),
                generated,
                std::io::IsTerminal::is_terminal(&std::io::stdout()),
            )
        );
        gleaner_server::serve(listener, &config, shutdown_signal()).await?;
        println!("stopped");
        Ok(())
    })
}

/// Completes on ctrl-c (SIGINT) or, on Unix, SIGTERM (a service manager's stop).
async fn shutdown_signal() {
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
