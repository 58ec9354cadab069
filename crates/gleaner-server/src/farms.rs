//! Many farms on one server (`gleaner serve --farms DIR`): every subdirectory of `DIR` that
//! holds a `gleaner.toml` is a farm (a project, on SQLite or in a PostgreSQL schema), served
//! under `/api/v1/farms/{farm}/...` with the same endpoints as one project's `/api/v1/...`,
//! and guarded by per-farm tokens with a read or write scope.
//!
//! - **Tokens** ([`FarmTokens`]): a tokens file (`DIR/tokens` unless `--tokens FILE`) holds one
//!   line per token, `farm scope sha256-hex`: only the SHA-256 of each token is stored, so the
//!   file reveals none. Tokens are drawn from 256 random bits ([`new_token_line`]), which a
//!   fast hash suffices for (nothing to brute-force). A request's bearer token is hashed and
//!   compared with every stored hash in constant time; it is never logged or printed.
//! - **Access**: every farm request needs a token of that farm, checked from the headers
//!   before anything else (the body is not read): none or an unknown one is 401 whatever the
//!   farm (existing or not); another farm's token gets the same 404 as a farm that does not
//!   exist, so a token reveals no farm but its own. A read-scope token reads and computes
//!   (previews, dry runs, simulations, reconstructions); writes need the write scope (403).
//! - **Dispatch** ([`Farms::router`]): the request's path is rewritten to the single-project
//!   path (`/api/v1/farms/north/plan` → `/api/v1/plan`) and handed to that farm's router,
//!   whose [`AppState`] has its own pool of open projects, write queue and read cache; the
//!   planning slot (one search at a time) is shared by every farm of the server.
//! - **Replicas**: several servers may serve the same farms directory over one PostgreSQL
//!   database (each farm's `database = "postgres://…#farm"`): the use cases hold the farm's
//!   exclusion in the database (`Project::exclusive`, PostgreSQL's advisory lock), so plans
//!   and records on one farm are serialised across replicas, not only within one server.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use axum::Router;
use axum::extract::{Request, State};
use axum::http::{HeaderMap, Uri, header};
use axum::response::{IntoResponse, Response};
use sha2::{Digest, Sha256};
use subtle::ConstantTimeEq;
use tower::ServiceExt as _;

use crate::error::ApiError;
use crate::state::AppState;
use crate::token::Token;
use crate::{ServerConfig, ServerError};

/// What a farm token may do.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, utoipa::ToSchema)]
#[serde(rename_all = "lowercase")]
pub enum Scope {
    /// Reads and computations that store nothing.
    Read,
    /// Everything a read token may, and writes (scorings, plans, explorations, uploads).
    Write,
}

impl Scope {
    /// `read` or `write`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Read => "read",
            Self::Write => "write",
        }
    }

    fn parse(text: &str) -> Option<Self> {
        match text {
            "read" => Some(Self::Read),
            "write" => Some(Self::Write),
            _ => None,
        }
    }
}

/// A request's access to its farm, checked by the dispatcher and handed to the farm's
/// handlers as a request extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FarmAccess {
    /// The token's scope.
    pub scope: Scope,
}

/// Whether `name` can name a farm: 1 to 63 characters `a-z`, `0-9`, `_`, `-`, starting with a
/// letter or digit (a URL path segment as it is, and a PostgreSQL schema once `-` becomes `_`).
pub fn valid_farm_name(name: &str) -> bool {
    let b = name.as_bytes();
    !b.is_empty()
        && b.len() <= 63
        && (b[0].is_ascii_lowercase() || b[0].is_ascii_digit())
        && b.iter()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || matches!(c, b'_' | b'-'))
}

/// One stored token: its farm, scope and SHA-256.
#[derive(Clone)]
struct Entry {
    farm: String,
    scope: Scope,
    hash: [u8; 32],
}

/// The farm tokens of a server, as read from its tokens file: hashes only. `Debug` shows the
/// farms and scopes, never a hash.
#[derive(Clone, Default)]
pub struct FarmTokens(Vec<Entry>);

impl std::fmt::Debug for FarmTokens {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list()
            .entries(self.0.iter().map(|e| (&e.farm, e.scope)))
            .finish()
    }
}

/// The SHA-256 of a token's text.
fn digest(token: &[u8]) -> [u8; 32] {
    Sha256::digest(token).into()
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

fn unhex(text: &str) -> Option<[u8; 32]> {
    if text.len() != 64 || !text.is_ascii() {
        return None;
    }
    let mut out = [0u8; 32];
    for (i, o) in out.iter_mut().enumerate() {
        *o = u8::from_str_radix(&text[2 * i..2 * i + 2], 16).ok()?;
    }
    Some(out)
}

/// A new token for `farm` with `scope`: the token (shown once to the operator) and the line
/// to add to the tokens file (its hash only).
pub fn new_token_line(farm: &str, scope: Scope) -> Result<(Token, String), ServerError> {
    if !valid_farm_name(farm) {
        return Err(ServerError::Config(format!(
            "farm name {farm:?}: expected 1-63 characters a-z, 0-9, _ and -, starting with a letter or digit"
        )));
    }
    let token = Token::random().map_err(|e| ServerError::Config(e.to_string()))?;
    let line = format!(
        "{farm} {} {}",
        scope.name(),
        hex(&digest(token.reveal().as_bytes()))
    );
    Ok((token, line))
}

impl FarmTokens {
    /// Parses a tokens file's text: one `farm scope sha256-hex` per line (blank lines and
    /// `#` comments ignored). Errors name the line; a line never echoes its hash.
    pub fn parse(text: &str) -> Result<Self, String> {
        let mut out: Vec<Entry> = Vec::new();
        for (i, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let n = i + 1;
            let parts: Vec<&str> = line.split_whitespace().collect();
            let [farm, scope, hash] = parts[..] else {
                return Err(format!(
                    "line {n}: expected `farm scope sha256-hex` (three fields), found {}",
                    parts.len()
                ));
            };
            if !valid_farm_name(farm) {
                return Err(format!("line {n}: farm name {farm:?} is not valid"));
            }
            let scope = Scope::parse(scope)
                .ok_or_else(|| format!("line {n}: scope {scope:?}: expected read or write"))?;
            let hash = unhex(hash).ok_or_else(|| {
                format!("line {n}: expected the token's SHA-256 as 64 hex digits")
            })?;
            if out.iter().any(|e| e.hash == hash) {
                return Err(format!("line {n}: the same token is listed twice"));
            }
            out.push(Entry {
                farm: farm.to_string(),
                scope,
                hash,
            });
        }
        Ok(Self(out))
    }

    /// Reads a tokens file.
    pub fn load(path: &Path) -> Result<Self, ServerError> {
        let text = std::fs::read_to_string(path).map_err(|e| {
            ServerError::Config(format!(
                "{}: cannot read the tokens file: {e}",
                path.display()
            ))
        })?;
        Self::parse(&text).map_err(|e| ServerError::Config(format!("{}: {e}", path.display())))
    }

    /// The farm and scope of the token `given`, if it is one of these: hashed, then compared
    /// with every stored hash in constant time (each comparison, and the loop over all of
    /// them, whatever matches).
    pub fn find(&self, given: &[u8]) -> Option<(&str, Scope)> {
        let h = digest(given);
        let mut found = None;
        for e in &self.0 {
            let same: bool = e.hash.ct_eq(&h).into();
            if same && found.is_none() {
                found = Some((e.farm.as_str(), e.scope));
            }
        }
        found
    }

    /// The farms the tokens name, sorted, each once.
    pub fn farms(&self) -> Vec<&str> {
        let mut f: Vec<&str> = self.0.iter().map(|e| e.farm.as_str()).collect();
        f.sort_unstable();
        f.dedup();
        f
    }

    /// Number of tokens.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

/// The bearer token of a request: `Ok(None)` without `Authorization`, 401 for another scheme
/// or an empty token (the scheme in any case, RFC 7235).
fn bearer(headers: &HeaderMap) -> Result<Option<&[u8]>, ApiError> {
    let Some(value) = headers.get(header::AUTHORIZATION) else {
        return Ok(None);
    };
    let bytes = value.as_bytes();
    let (scheme, rest) = match bytes.iter().position(|&b| b == b' ') {
        Some(i) => (&bytes[..i], &bytes[i..]),
        None => (bytes, &b""[..]),
    };
    let given = rest.trim_ascii();
    if !scheme.eq_ignore_ascii_case(b"bearer") || given.is_empty() {
        return Err(ApiError::unauthorized(
            "expected Authorization: Bearer <farm token>",
        ));
    }
    Ok(Some(given))
}

/// One farm: its state and its router (the single-project API over that state).
struct Farm {
    state: AppState,
    router: Router,
}

/// The farms of a server: their states and routers, and the tokens.
#[derive(Clone)]
pub struct Farms(Arc<FarmsInner>);

struct FarmsInner {
    farms: BTreeMap<String, Farm>,
    tokens: FarmTokens,
}

impl std::fmt::Debug for Farms {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Farms")
            .field("farms", &self.0.farms.keys().collect::<Vec<_>>())
            .field("tokens", &self.0.tokens)
            .finish()
    }
}

/// The farm directories in `dir`: every subdirectory holding a `gleaner.toml`, by name.
/// A farm directory whose name cannot name a farm is refused.
pub fn farm_dirs(dir: &Path) -> Result<BTreeMap<String, PathBuf>, ServerError> {
    let entries = std::fs::read_dir(dir).map_err(|e| {
        ServerError::Config(format!(
            "{}: cannot read the farms directory: {e}",
            dir.display()
        ))
    })?;
    let mut out = BTreeMap::new();
    for e in entries {
        let e = e.map_err(|e| ServerError::Config(format!("{}: {e}", dir.display())))?;
        let path = e.path();
        if !path.is_dir() || !path.join("gleaner.toml").is_file() {
            continue;
        }
        let name = e.file_name().to_string_lossy().to_string();
        if !valid_farm_name(&name) {
            return Err(ServerError::Config(format!(
                "{}: a farm's directory name must be 1-63 characters a-z, 0-9, _ and -, starting with a letter or digit",
                path.display()
            )));
        }
        out.insert(name, path);
    }
    Ok(out)
}

impl Farms {
    /// Opens every farm of `config.farms` (each with `config.pool_size` projects; one planning
    /// slot shared by all) and reads the tokens (`config.tokens_file`, else `tokens` in the
    /// farms directory). Refuses a directory without farms, a tokens file naming a farm that
    /// is not there, and a server token (farms take only farm tokens).
    pub fn open(config: &ServerConfig) -> Result<Self, ServerError> {
        let dir = config
            .farms
            .as_deref()
            .ok_or_else(|| ServerError::Config("no farms directory given".into()))?;
        let dirs = farm_dirs(dir)?;
        if dirs.is_empty() {
            return Err(ServerError::Config(format!(
                "{}: no farm in it (a farm is a subdirectory holding a gleaner.toml)",
                dir.display()
            )));
        }
        let tokens_path = config
            .tokens_file
            .clone()
            .unwrap_or_else(|| dir.join("tokens"));
        let tokens = FarmTokens::load(&tokens_path)?;
        if let Some(unknown) = tokens.farms().into_iter().find(|f| !dirs.contains_key(*f)) {
            return Err(ServerError::Config(format!(
                "{}: a token for farm {unknown:?}, which is not in {}",
                tokens_path.display(),
                dir.display()
            )));
        }
        let planning = Arc::new(tokio::sync::Semaphore::new(1));
        let doc = Arc::<str>::from(
            crate::farms_openapi()
                .to_json()
                .unwrap_or_else(|_| "{}".to_string()),
        );
        let mut farms = BTreeMap::new();
        for (name, path) in dirs {
            let state = AppState::for_farm(config, &path, Arc::clone(&planning))
                .map_err(|e| ServerError::Config(format!("farm {name}: {e}")))?;
            let router = crate::project_router(state.clone(), config, Arc::clone(&doc), false);
            farms.insert(name, Farm { state, router });
        }
        Ok(Self(Arc::new(FarmsInner { farms, tokens })))
    }

    /// The farms' names, sorted.
    pub fn names(&self) -> Vec<&str> {
        self.0.farms.keys().map(String::as_str).collect()
    }

    /// A farm's state (to watch it in tests).
    pub fn state(&self, farm: &str) -> Option<&AppState> {
        self.0.farms.get(farm).map(|f| &f.state)
    }

    /// Every farm's state.
    pub(crate) fn states(&self) -> Vec<AppState> {
        self.0.farms.values().map(|f| f.state.clone()).collect()
    }

    /// The farms' routes: `GET /api/v1/farms` (the caller's farm) and everything under
    /// `/api/v1/farms/{farm}/`.
    pub(crate) fn router(&self) -> Router {
        // The dispatcher is the fallback, not a `{*rest}` route: a route's path parameters
        // would stay in the request and add to the farm's own (`/missions/{id}`).
        Router::new()
            .route("/api/v1/farms", axum::routing::get(farms_list))
            .fallback(dispatch)
            .with_state(self.clone())
    }

    /// The farm and scope of a request's token: 401 without one or with one that is no
    /// farm's.
    fn access(&self, headers: &HeaderMap) -> Result<(&str, Scope), ApiError> {
        let given = bearer(headers)?.ok_or_else(|| {
            ApiError::unauthorized("a farm's API needs Authorization: Bearer <farm token>")
        })?;
        self.0
            .tokens
            .find(given)
            .ok_or_else(|| ApiError::unauthorized("the bearer token is not one of this server's"))
    }
}

/// The same answer for a farm that does not exist and for another farm's token.
fn no_such_farm() -> ApiError {
    ApiError::not_found(Some("farm"), "no such farm for this token")
}

/// The farms this token opens (one), with its scope.
#[derive(Debug, serde::Serialize, utoipa::ToSchema)]
pub struct FarmDoc {
    /// The farm's name (its path segment).
    pub farm: String,
    /// `read` or `write`.
    pub scope: Scope,
}

/// Lists the farm the bearer token opens, with its scope (a token never learns of another
/// farm).
#[utoipa::path(get, path = "/api/v1/farms", tag = "farms", security(("bearer" = [])),
    responses((status = 200, body = Vec<FarmDoc>), (status = 401, body = crate::ErrorBody)))]
pub async fn farms_list(State(farms): State<Farms>, headers: HeaderMap) -> Response {
    match farms.access(&headers) {
        Ok((farm, scope)) => axum::Json(vec![FarmDoc {
            farm: farm.to_string(),
            scope,
        }])
        .into_response(),
        Err(e) => e.into_response(),
    }
}

/// The farms router's fallback: `/api/v1/farms/{farm}/{rest}` checks the token against the farm, then answers as the
/// farm's own `/api/v1/{rest}`.
async fn dispatch(State(farms): State<Farms>, mut req: Request) -> Response {
    if !req.uri().path().starts_with("/api/v1/farms/") {
        return ApiError::not_found(
            None,
            "no such page or endpoint: a farms server answers under /api/v1/farms/{farm}/ (see /api/v1/openapi.json)",
        )
        .into_response();
    }
    let (farm, scope) = match farms.access(req.headers()) {
        Ok(a) => a,
        Err(e) => return e.into_response(),
    };
    let path = req.uri().path();
    let rest = path.strip_prefix("/api/v1/farms/").unwrap_or("");
    let (name, tail) = rest.split_once('/').unwrap_or((rest, ""));
    // Compared in full, so a farm's name is learnt only with its token.
    let Some(target) = farms.0.farms.get(name).filter(|_| name == farm) else {
        return no_such_farm().into_response();
    };
    let rewritten = match req.uri().query() {
        Some(q) => format!("/api/v1/{tail}?{q}"),
        None => format!("/api/v1/{tail}"),
    };
    match rewritten.parse::<Uri>() {
        Ok(uri) => *req.uri_mut() = uri,
        Err(_) => {
            return ApiError::bad_request(Some("path"), "the path is not a valid URI")
                .into_response();
        }
    }
    req.extensions_mut().insert(FarmAccess { scope });
    match target.router.clone().oneshot(req).await {
        Ok(r) => r,
        Err(never) => match never {},
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_are_stored_hashed_and_found_by_their_hash() {
        let (t, line) = new_token_line("north", Scope::Write).unwrap();
        assert!(!line.contains(t.reveal()));
        let (r, read_line) = new_token_line("south-2", Scope::Read).unwrap();
        let file = format!("# farm scope sha256\n\n{line}\n{read_line}\n");
        let tokens = FarmTokens::parse(&file).unwrap();
        assert_eq!(tokens.len(), 2);
        assert_eq!(
            tokens.find(t.reveal().as_bytes()),
            Some(("north", Scope::Write))
        );
        assert_eq!(
            tokens.find(r.reveal().as_bytes()),
            Some(("south-2", Scope::Read))
        );
        assert_eq!(tokens.find(b"not-a-token-at-all"), None);
        assert_eq!(tokens.farms(), vec!["north", "south-2"]);
        assert!(!format!("{tokens:?}").contains(&line[line.len() - 64..]));
        for (bad, why) in [
            ("north write", "three fields"),
            ("North write 00", "not valid"),
            ("north admin 00", "scope"),
            ("north read abc", "64 hex"),
        ] {
            let e = FarmTokens::parse(bad).unwrap_err();
            assert!(e.contains(why), "{bad}: {e}");
        }
        assert!(
            FarmTokens::parse(&format!("{line}\n{line}"))
                .unwrap_err()
                .contains("twice")
        );
        assert!(new_token_line("../etc", Scope::Read).is_err());
    }

    #[test]
    fn bearer_scheme_in_any_case() {
        let mut h = HeaderMap::new();
        assert_eq!(bearer(&h).unwrap(), None);
        h.insert(header::AUTHORIZATION, "bEaReR  abc".parse().unwrap());
        assert_eq!(bearer(&h).unwrap(), Some(&b"abc"[..]));
        for bad in ["Basic abc", "Bearer", "Bearer   "] {
            h.insert(header::AUTHORIZATION, bad.parse().unwrap());
            assert_eq!(bearer(&h).unwrap_err().status, 401, "{bad}");
        }
    }
}
