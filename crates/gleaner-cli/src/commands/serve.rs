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
    /// Serve many farms: every subdirectory of DIR holding a gleaner.toml is a farm, served
    /// under /api/v1/farms/{farm}/ to the holders of its tokens; the dashboard at / picks a
    /// farm among those of the farm tokens given to it.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["project", "token_file", "read_only"])]
    farms: Option<PathBuf>,
    /// The farms' tokens file (lines `farm scope sha256-hex`; `gleaner farm-token` adds
    /// them) [default: DIR/tokens].
    #[arg(long, value_name = "FILE", requires = "farms")]
    tokens: Option<PathBuf>,
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
/// that cannot be done, and the server then runs with glibc's defaults.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn with_malloc_tunables() {
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
    eprintln!("gleaner serve: running with glibc's malloc defaults (re-executing failed: {err})");
}

/// Runs the server until ctrl-c or SIGTERM; prints the dashboard's address (with the token in the URL's
/// fragment when the token was generated here, so it never reaches a log).
pub fn run(args: ServeArgs) -> Result<()> {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    with_malloc_tunables();
    let mut generated = false;
    let token = if args.farms.is_some() {
        // Farm tokens only (GLEANER_TOKEN is for one project).
        None
    } else if args.read_only {
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
        farms: args.farms,
        tokens_file: args.tokens,
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
        if config.farms.is_some() {
            let farms = gleaner_server::Farms::open(&config)?;
            println!(
                "farms: {}\nAPI: http://{addr}/api/v1/farms/{{farm}}/ (a farm token in Authorization: Bearer) · http://{addr}/api/v1/openapi.json · stop with ctrl-c",
                farms.names().join(", ")
            );
            gleaner_server::serve_farms(listener, &config, farms, shutdown_signal()).await?;
            println!("stopped");
            return Ok(());
        }
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

// The arguments of `gleaner farm-token` (no doc comment: the variant's is the help).
#[derive(clap::Args)]
pub struct FarmTokenArgs {
    /// The farms directory (the tokens file is DIR/tokens unless --tokens).
    #[arg(long, value_name = "DIR")]
    farms: PathBuf,
    /// The farm the token opens (a subdirectory of DIR).
    #[arg(long)]
    farm: String,
    /// What the token may do: read (reads and previews) or write (also saves and uploads).
    #[arg(long, value_parser = ["read", "write"])]
    scope: String,
    /// The tokens file [default: DIR/tokens].
    #[arg(long, value_name = "FILE")]
    tokens: Option<PathBuf>,
}

/// Draws a token for a farm, appends its hash to the tokens file and prints the token once
/// (the file keeps only its SHA-256). A running server reads the file at start-up.
pub fn farm_token(args: FarmTokenArgs) -> Result<()> {
    use std::io::Write as _;
    let farms = gleaner_server::farms::farm_dirs(&args.farms)?;
    if !farms.contains_key(&args.farm) {
        anyhow::bail!(
            "{}: no farm {:?} in it (farms: {})",
            args.farms.display(),
            args.farm,
            farms.keys().cloned().collect::<Vec<_>>().join(", ")
        );
    }
    let scope = match args.scope.as_str() {
        "read" => gleaner_server::Scope::Read,
        _ => gleaner_server::Scope::Write,
    };
    let path = args.tokens.unwrap_or_else(|| args.farms.join("tokens"));
    let (token, line) = gleaner_server::farms::new_token_line(&args.farm, scope)?;
    let mut file = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&path)
        .with_context(|| format!("{}: cannot open the tokens file", path.display()))?;
    writeln!(file, "{line}").with_context(|| format!("{}: cannot write", path.display()))?;
    eprintln!(
        "added a {} token for farm {} to {} (restart the servers to use it); the token, shown once:",
        scope.name(),
        args.farm,
        path.display()
    );
    println!("{}", token.reveal());
    Ok(())
}
