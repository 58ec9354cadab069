//! `gleaner serve` and `farm-token`: parses the flags and runs the HTTP API and dashboard
//! (`gleaner_server::start`) until ctrl-c.

use std::net::SocketAddr;
use std::path::PathBuf;

use anyhow::Result;
use gleaner_server::{ServerConfig, start};

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

/// Runs the server until ctrl-c or SIGTERM (`gleaner_server::start`); prints the dashboard's
/// address (with the token in the URL's fragment when the token was generated here, so it
/// never reaches a log).
pub fn run(args: ServeArgs) -> Result<()> {
    start::with_malloc_tunables();
    let config = ServerConfig {
        project: args.project,
        farms: args.farms,
        tokens_file: args.tokens,
        addr: args.addr,
        cors_origins: args.cors_origins,
        allowed_hosts: args.allowed_hosts,
        basemap_url: args.basemap_url,
        max_upload_bytes: args.max_upload_mib.saturating_mul(1 << 20),
        max_time_limit_s: args.max_time_limit,
        ..ServerConfig::new(PathBuf::new())
    };
    let source = start::TokenSource {
        read_only: args.read_only,
        file: args.token_file.as_deref(),
        env: std::env::var_os("GLEANER_TOKEN"),
    };
    let (token, generated) = start::write_token(&config, source)?;
    start::serve_until_stopped(ServerConfig { token, ..config }, generated)?;
    Ok(())
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
    let scope = match args.scope.as_str() {
        "read" => gleaner_server::Scope::Read,
        _ => gleaner_server::Scope::Write,
    };
    let (token, path) = start::add_farm_token(&args.farms, &args.farm, scope, args.tokens)?;
    eprintln!(
        "added a {} token for farm {} to {} (restart the servers to use it); the token, shown once:",
        scope.name(),
        args.farm,
        path.display()
    );
    println!("{}", token.reveal());
    Ok(())
}
