//! Bearer tokens with roles, and the middleware that checks them.
//!
//! Tokens are configured as `ROLE:TOKEN` pairs (flags, an environment variable, a file) and
//! kept only as SHA-256 digests. A presented token is hashed and its digest compared with
//! every configured digest in constant time, so neither the prefix nor the length of a guess
//! shows in the time an answer takes.
//!
//! Roles are ordered, `admin` ⊇ `write` ⊇ `read`: a route that needs `write` admits `write`
//! and `admin` tokens.
//!
//! # Wiring
//!
//! ```no_run
//! use std::sync::Arc;
//! use axum::{Router, middleware::from_fn_with_state, routing::{get, post}};
//! use winged::server::auth::{Guard, Role, Tokens, guard, guard_by_method};
//!
//! # async fn h() {}
//! let tokens = Arc::new(Tokens::none());
//! // One role for every route of a router (route_layer: unmatched paths stay 404).
//! let admin: Router = Router::new()
//!     .route("/v1/admin/snapshot", post(h))
//!     .route_layer(from_fn_with_state(Guard::new(tokens.clone(), Role::Admin), guard));
//! // Reads (GET, HEAD, OPTIONS) need `read`, every other method needs `write`.
//! let api: Router = Router::new()
//!     .route("/v1/bodies", get(h).post(h))
//!     .route_layer(from_fn_with_state(tokens.clone(), guard_by_method));
//! let app = api.merge(admin).route("/healthz", get(h));
//! ```
//!
//! Handlers read the caller's role with `Extension<Role>`.

use std::collections::HashMap;
use std::fmt;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::sync::Arc;

use axum::extract::{Request, State};
use axum::http::{HeaderValue, Method, StatusCode, header};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use sha2::{Digest, Sha256};
use subtle::{ConditionallySelectable, ConstantTimeEq};

use super::problem::{Problem, refused_unread};

/// What a caller may do. Ordered: `Read < Write < Admin`, and a higher role includes every
/// lower one.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Role {
    /// Look at the world.
    Read,
    /// Look at and change the world.
    Write,
    /// Everything, including administrative routes.
    Admin,
}

impl Role {
    /// The role a request with `method` needs under [`guard_by_method`]: `Read` for the safe
    /// methods GET, HEAD and OPTIONS, `Write` for every other method.
    pub fn for_method(method: &Method) -> Role {
        if method == Method::GET || method == Method::HEAD || method == Method::OPTIONS {
            Role::Read
        } else {
            Role::Write
        }
    }

    /// The name used in configuration and answers: `read`, `write` or `admin`.
    pub fn as_str(self) -> &'static str {
        match self {
            Role::Read => "read",
            Role::Write => "write",
            Role::Admin => "admin",
        }
    }

    /// Encoding for the constant-time lookup; 0 stands for "no role".
    fn code(self) -> u8 {
        match self {
            Role::Read => 1,
            Role::Write => 2,
            Role::Admin => 3,
        }
    }

    fn from_code(code: u8) -> Option<Role> {
        match code {
            1 => Some(Role::Read),
            2 => Some(Role::Write),
            3 => Some(Role::Admin),
            _ => None,
        }
    }
}

impl fmt::Display for Role {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// A role name that is not `read`, `write` or `admin`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown role; expected read, write or admin")]
pub struct UnknownRole;

impl FromStr for Role {
    type Err = UnknownRole;

    /// Parses `read`, `write` or `admin`, ignoring ASCII case.
    fn from_str(s: &str) -> Result<Role, UnknownRole> {
        [Role::Read, Role::Write, Role::Admin]
            .into_iter()
            .find(|r| s.eq_ignore_ascii_case(r.as_str()))
            .ok_or(UnknownRole)
    }
}

/// Where a token entry came from, for error messages (never the token itself).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Origin {
    /// The n-th token flag (1-based).
    Flag(usize),
    /// The n-th comma-separated item of the environment variable (1-based).
    Env(usize),
    /// A line (1-based) of a token file.
    File {
        /// The file.
        path: PathBuf,
        /// The line number.
        line: usize,
    },
}

impl fmt::Display for Origin {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Origin::Flag(n) => write!(f, "token flag #{n}"),
            Origin::Env(n) => write!(f, "token environment variable, item {n}"),
            Origin::File { path, line } => write!(f, "{}, line {line}", path.display()),
        }
    }
}

/// Why the token configuration or the listening address was refused. Messages name where
/// the problem is and never contain a token.
#[derive(Debug, thiserror::Error)]
pub enum AuthError {
    /// An entry is not `ROLE:TOKEN` (or `ROLE TOKEN` in a file), or its token is unusable.
    #[error("{at}: {reason}")]
    Malformed {
        /// Where the entry is.
        at: Origin,
        /// What is wrong with it.
        reason: &'static str,
    },
    /// The same token was given twice with different roles.
    #[error("{at}: the same token was already given with role {first_role} at {first}")]
    Conflict {
        /// The second occurrence.
        at: Origin,
        /// The first occurrence.
        first: Origin,
        /// The role given at the first occurrence.
        first_role: Role,
    },
    /// The token file could not be read.
    #[error("cannot read token file {}: {error}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's reason.
        #[source]
        error: std::io::Error,
    },
    /// No tokens are configured and the address is reachable from other machines.
    #[error(
        "refusing to listen on {addr} without bearer tokens: only loopback addresses may be \
         served unauthenticated (configure tokens with WINGED_TOKENS, --tokens-file or \
         --token, or pass --insecure)"
    )]
    UnsafeBind {
        /// The address asked for.
        addr: SocketAddr,
    },
}

type Digest32 = [u8; 32];

fn digest(token: &str) -> Digest32 {
    Sha256::digest(token.as_bytes()).into()
}

/// One configured token: its digest and role.
#[derive(Clone)]
struct Entry {
    digest: Digest32,
    role: Role,
}

/// The configured bearer tokens, held as SHA-256 digests with their roles.
///
/// Invariant: no two entries have the same digest.
#[derive(Clone, Default)]
pub struct Tokens {
    entries: Vec<Entry>,
}

impl fmt::Debug for Tokens {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Tokens")
            .field("len", &self.entries.len())
            .finish_non_exhaustive()
    }
}

impl Tokens {
    /// No tokens: authentication is off (see [`check_bind`]).
    pub fn none() -> Tokens {
        Tokens::default()
    }

    /// True when no token is configured.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// The number of distinct tokens.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Collects tokens from every source.
    ///
    /// - each of `flags` is `ROLE:TOKEN`;
    /// - `env` is a comma-separated list of `ROLE:TOKEN` items (blank items are skipped);
    /// - `file` holds one `ROLE TOKEN` or `ROLE:TOKEN` per line; blank lines and lines whose
    ///   first non-blank character is `#` are ignored.
    ///
    /// `ROLE` is `read`, `write` or `admin`. Tokens must be non-empty printable ASCII without
    /// whitespace (what fits an `Authorization: Bearer` header); surrounding whitespace is
    /// trimmed.
    ///
    /// Postcondition: on success every given token maps to its role; a token given more than
    /// once with the same role counts once.
    ///
    /// # Errors
    /// [`AuthError::Malformed`] or [`AuthError::Conflict`] (the same token with two roles),
    /// naming the source and line; [`AuthError::Io`] if the file cannot be read.
    pub fn from_sources(
        flags: &[String],
        env: Option<&str>,
        file: Option<&Path>,
    ) -> Result<Tokens, AuthError> {
        let mut b = Builder::default();
        for (i, flag) in flags.iter().enumerate() {
            b.add_colon_pair(flag, Origin::Flag(i + 1))?;
        }
        if let Some(env) = env {
            for (i, item) in env.split(',').enumerate() {
                if !item.trim().is_empty() {
                    b.add_colon_pair(item, Origin::Env(i + 1))?;
                }
            }
        }
        if let Some(path) = file {
            let text = std::fs::read_to_string(path).map_err(|error| AuthError::Io {
                path: path.to_path_buf(),
                error,
            })?;
            for (i, line) in text.lines().enumerate() {
                let line = line.trim();
                if line.is_empty() || line.starts_with('#') {
                    continue;
                }
                let at = Origin::File {
                    path: path.to_path_buf(),
                    line: i + 1,
                };
                let Some(sep) = line.find(|c: char| c == ':' || c.is_whitespace()) else {
                    return Err(AuthError::Malformed {
                        at,
                        reason: "expected ROLE TOKEN or ROLE:TOKEN",
                    });
                };
                let sep_len = line[sep..].chars().next().map_or(1, char::len_utf8);
                b.add(&line[..sep], &line[sep + sep_len..], at)?;
            }
        }
        Ok(Tokens { entries: b.entries })
    }

    /// The role of `presented`, or `None` if it is not a configured token.
    ///
    /// The presented token is hashed once, and its digest is compared with every configured
    /// digest in constant time, without stopping at a match; the role is picked with a
    /// constant-time select. The time taken depends only on the length of `presented` (known
    /// to the caller) and the number of configured tokens, never on how much of a secret a
    /// guess shares.
    pub fn role_of(&self, presented: &str) -> Option<Role> {
        let d = digest(presented);
        let mut code = 0u8;
        for e in &self.entries {
            let same = d.ct_eq(&e.digest);
            code = u8::conditional_select(&code, &e.role.code(), same);
        }
        Role::from_code(code)
    }
}

/// Accumulates entries and refuses conflicts.
#[derive(Default)]
struct Builder {
    entries: Vec<Entry>,
    seen: HashMap<Digest32, (Role, Origin)>,
}

impl Builder {
    fn add_colon_pair(&mut self, item: &str, at: Origin) -> Result<(), AuthError> {
        match item.trim().split_once(':') {
            Some((role, token)) => self.add(role, token, at),
            None => Err(AuthError::Malformed {
                at,
                reason: "expected ROLE:TOKEN",
            }),
        }
    }

    fn add(&mut self, role: &str, token: &str, at: Origin) -> Result<(), AuthError> {
        let malformed = |reason| AuthError::Malformed {
            at: at.clone(),
            reason,
        };
        let role: Role = role
            .trim()
            .parse()
            .map_err(|_| malformed("unknown role; expected read, write or admin"))?;
        let token = token.trim();
        if token.is_empty() {
            return Err(malformed("empty token"));
        }
        if token.chars().any(char::is_whitespace) {
            return Err(malformed("whitespace inside the token"));
        }
        if !token.bytes().all(|b| b.is_ascii_graphic()) {
            return Err(malformed("the token must be printable ASCII"));
        }
        let d = digest(token);
        match self.seen.get(&d) {
            Some((first_role, _)) if *first_role == role => Ok(()),
            Some((first_role, first)) => Err(AuthError::Conflict {
                at,
                first: first.clone(),
                first_role: *first_role,
            }),
            None => {
                self.seen.insert(d, (role, at));
                self.entries.push(Entry { digest: d, role });
                Ok(())
            }
        }
    }
}

/// Refuses to serve unauthenticated on an address other machines can reach.
///
/// Precondition: `tokens` is the configuration the server will run with.
/// Postcondition: `Ok` iff tokens are configured, or `addr` is a loopback address (IPv4,
/// IPv6 or IPv4-mapped IPv6), or `insecure` is set.
///
/// # Errors
/// [`AuthError::UnsafeBind`] otherwise (note that `0.0.0.0` and `::` are not loopback).
pub fn check_bind(addr: &SocketAddr, tokens: &Tokens, insecure: bool) -> Result<(), AuthError> {
    if !tokens.is_empty() || insecure || addr.ip().to_canonical().is_loopback() {
        Ok(())
    } else {
        Err(AuthError::UnsafeBind { addr: *addr })
    }
}

/// State for [`guard`]: the tokens, and the least role the guarded routes need.
#[derive(Clone, Debug)]
pub struct Guard {
    /// The configured tokens; when empty every request passes.
    pub tokens: Arc<Tokens>,
    /// The least role admitted.
    pub need: Role,
}

impl Guard {
    /// A guard admitting `need` and higher roles.
    pub fn new(tokens: Arc<Tokens>, need: Role) -> Guard {
        Guard { tokens, need }
    }
}

/// Middleware: admits requests whose bearer token holds at least `need`.
///
/// Use with `route_layer(axum::middleware::from_fn_with_state(Guard { .. }, guard))`.
///
/// - No tokens configured: every request passes, as [`Role::Admin`].
/// - Missing or malformed `Authorization: Bearer <token>`, or an unknown token: 401
///   problem+json with `WWW-Authenticate: Bearer realm="winged"`.
/// - A known token whose role is below `need`: 403 problem+json naming the role needed.
///
/// Postcondition: a request reaching the inner service carries the caller's [`Role`] in its
/// extensions.
pub async fn guard(State(g): State<Guard>, req: Request, next: Next) -> Response {
    admit(&g.tokens, g.need, req, next).await
}

/// Middleware like [`guard`] whose needed role follows the method ([`Role::for_method`]):
/// `read` for GET, HEAD and OPTIONS, `write` for every other method.
///
/// Use with `route_layer(axum::middleware::from_fn_with_state(tokens, guard_by_method))`
/// where `tokens: Arc<Tokens>`.
pub async fn guard_by_method(
    State(tokens): State<Arc<Tokens>>,
    req: Request,
    next: Next,
) -> Response {
    let need = Role::for_method(req.method());
    admit(&tokens, need, req, next).await
}

async fn admit(tokens: &Tokens, need: Role, mut req: Request, next: Next) -> Response {
    let role = if tokens.is_empty() {
        Role::Admin
    } else {
        let Some(presented) = bearer(&req) else {
            return unauthorized(
                "send Authorization: Bearer <token>",
                r#"Bearer realm="winged""#,
            );
        };
        let Some(role) = tokens.role_of(presented) else {
            return unauthorized(
                "the bearer token is not known",
                r#"Bearer realm="winged", error="invalid_token""#,
            );
        };
        if role < need {
            let mut res = Problem::new(
                StatusCode::FORBIDDEN,
                "forbidden",
                "Forbidden",
                format!("this route needs the {need} role; the token holds {role}"),
            )
            .into_response();
            res.headers_mut().insert(
                header::WWW_AUTHENTICATE,
                HeaderValue::from_static(r#"Bearer realm="winged", error="insufficient_scope""#),
            );
            return refused_unread(res);
        }
        role
    };
    req.extensions_mut().insert(role);
    next.run(req).await
}

/// The token of the single `Authorization: Bearer <token>` header, if well-formed.
fn bearer(req: &Request) -> Option<&str> {
    let mut values = req.headers().get_all(header::AUTHORIZATION).iter();
    let value = values.next()?;
    if values.next().is_some() {
        return None;
    }
    let value = value.to_str().ok()?;
    let (scheme, token) = value.split_once(' ')?;
    if !scheme.eq_ignore_ascii_case("bearer") {
        return None;
    }
    let token = token.trim_start_matches(' ');
    (!token.is_empty() && token.bytes().all(|b| b.is_ascii_graphic())).then_some(token)
}

fn unauthorized(detail: &'static str, challenge: &'static str) -> Response {
    let mut res = Problem::new(
        StatusCode::UNAUTHORIZED,
        "unauthorized",
        "Unauthorized",
        detail,
    )
    .into_response();
    res.headers_mut().insert(
        header::WWW_AUTHENTICATE,
        HeaderValue::from_static(challenge),
    );
    refused_unread(res)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    fn tokens(flags: &[&str]) -> Result<Tokens, AuthError> {
        let flags: Vec<String> = flags.iter().map(|s| s.to_string()).collect();
        Tokens::from_sources(&flags, None, None)
    }

    #[test]
    fn roles_are_ordered_and_named() {
        assert!(Role::Read < Role::Write && Role::Write < Role::Admin);
        for r in [Role::Read, Role::Write, Role::Admin] {
            assert_eq!(r.to_string().parse::<Role>(), Ok(r));
        }
        assert_eq!("ADMIN".parse::<Role>(), Ok(Role::Admin));
        assert_eq!("root".parse::<Role>(), Err(UnknownRole));
        assert_eq!(Role::for_method(&Method::GET), Role::Read);
        assert_eq!(Role::for_method(&Method::HEAD), Role::Read);
        assert_eq!(Role::for_method(&Method::PATCH), Role::Write);
        assert_eq!(Role::for_method(&Method::DELETE), Role::Write);
    }

    #[test]
    fn tokens_from_every_source() {
        let mut file = tempfile::NamedTempFile::new().unwrap();
        writeln!(
            file,
            "# operators\n\nadmin   root-token\n  write:w:with:colons  "
        )
        .unwrap();
        let t = Tokens::from_sources(
            &["read:r1".to_string()],
            Some("read:r2, write:w2,,"),
            Some(file.path()),
        )
        .unwrap();
        assert_eq!(t.len(), 5);
        assert_eq!(t.role_of("r1"), Some(Role::Read));
        assert_eq!(t.role_of("r2"), Some(Role::Read));
        assert_eq!(t.role_of("w2"), Some(Role::Write));
        assert_eq!(t.role_of("root-token"), Some(Role::Admin));
        assert_eq!(t.role_of("w:with:colons"), Some(Role::Write));
        assert_eq!(t.role_of("r3"), None);
        assert_eq!(t.role_of(""), None);
        assert_eq!(t.role_of("root-toke"), None);
    }

    #[test]
    fn bad_entries_are_refused_without_echoing_the_token() {
        let secret = "s3cr3t-value";
        for (flag, reason) in [
            (format!("read:{secret} more"), "whitespace"),
            ("read:".to_string(), "empty"),
            (format!("reader:{secret}"), "role"),
            (secret.to_string(), "ROLE:TOKEN"),
            (format!("read:{secret}\u{e9}"), "ASCII"),
        ] {
            let e = tokens(&["admin:ok", &flag]).unwrap_err();
            let msg = e.to_string();
            assert!(msg.contains("token flag #2"), "{msg}");
            assert!(msg.contains(reason), "{msg}");
            assert!(!msg.contains(secret), "the message leaks the token: {msg}");
        }
    }

    #[test]
    fn file_errors_name_the_line() {
        let mut file = tempfile::NamedTempFile::new().unwrap();
        writeln!(file, "read a\n# fine\nwrite b c").unwrap();
        let e = Tokens::from_sources(&[], None, Some(file.path())).unwrap_err();
        assert!(
            e.to_string()
                .ends_with("line 3: whitespace inside the token"),
            "{e}"
        );
        let missing = file.path().with_extension("absent");
        let e = Tokens::from_sources(&[], None, Some(&missing)).unwrap_err();
        assert!(matches!(e, AuthError::Io { .. }), "{e}");
    }

    #[test]
    fn one_token_two_roles_is_refused_same_role_twice_is_not() {
        let e = Tokens::from_sources(&["read:dup".into()], Some("admin:x,admin:dup"), None)
            .unwrap_err();
        match &e {
            AuthError::Conflict {
                at,
                first,
                first_role,
            } => {
                assert_eq!(*at, Origin::Env(2));
                assert_eq!(*first, Origin::Flag(1));
                assert_eq!(*first_role, Role::Read);
            }
            other => panic!("expected a conflict, got {other:?}"),
        }
        assert!(!e.to_string().contains("dup"), "{e}");
        let t = tokens(&["write:same", "write:same"]).unwrap();
        assert_eq!(t.len(), 1);
    }

    #[test]
    fn unauthenticated_serving_is_loopback_only() {
        let none = Tokens::none();
        let some = tokens(&["read:t"]).unwrap();
        for ok in ["127.0.0.1:8080", "[::1]:8080", "[::ffff:127.0.0.1]:1"] {
            let a: SocketAddr = ok.parse().unwrap();
            check_bind(&a, &none, false).unwrap();
        }
        for open in ["0.0.0.0:8080", "[::]:8080", "192.168.1.2:80"] {
            let a: SocketAddr = open.parse().unwrap();
            assert!(matches!(
                check_bind(&a, &none, false),
                Err(AuthError::UnsafeBind { .. })
            ));
            check_bind(&a, &none, true).unwrap();
            check_bind(&a, &some, false).unwrap();
        }
    }

    /// A tiny app behind the guards, served on a real loopback listener.
    mod http {
        use super::*;
        use axum::extract::Extension;
        use axum::middleware::from_fn_with_state;
        use axum::routing::get;
        use axum::{Router, routing::post};
        use serde_json::Value;

        async fn whoami(Extension(role): Extension<Role>) -> String {
            role.to_string()
        }

        fn app(tokens: Tokens) -> Router {
            let tokens = Arc::new(tokens);
            let admin =
                Router::new()
                    .route("/admin", post(whoami))
                    .route_layer(from_fn_with_state(
                        Guard::new(tokens.clone(), Role::Admin),
                        guard,
                    ));
            Router::new()
                .route("/thing", get(whoami).post(whoami))
                .route_layer(from_fn_with_state(tokens, guard_by_method))
                .merge(admin)
        }

        struct Answer {
            status: u16,
            challenge: Option<String>,
            content_type: Option<String>,
            body: String,
        }

        /// Serves `app` on 127.0.0.1:0 and sends each `(method, path, authorization)`.
        fn exchange(app: Router, requests: &[(&str, &str, Option<&str>)]) -> Vec<Answer> {
            let server =
                crate::server::background::Background::router("127.0.0.1:0".parse().unwrap(), app)
                    .unwrap();
            let base = server.base();
            let agent: ureq::Agent = ureq::Agent::config_builder()
                .http_status_as_error(false)
                .build()
                .into();
            let answers = requests
                .iter()
                .map(|(method, path, auth)| {
                    let mut req = axum::http::Request::builder()
                        .method(*method)
                        .uri(format!("{base}{path}"));
                    if let Some(a) = auth {
                        req = req.header("authorization", *a);
                    }
                    let mut res = agent.run(req.body(()).unwrap()).unwrap();
                    let header = |name: &str| {
                        res.headers()
                            .get(name)
                            .map(|v| v.to_str().unwrap().to_string())
                    };
                    let challenge = header("www-authenticate");
                    let content_type = header("content-type");
                    Answer {
                        status: res.status().as_u16(),
                        challenge,
                        content_type,
                        body: res.body_mut().read_to_string().unwrap(),
                    }
                })
                .collect();
            drop(agent);
            server.stop().unwrap();
            answers
        }

        #[test]
        fn without_tokens_everything_passes_as_admin() {
            let a = exchange(
                app(Tokens::none()),
                &[("GET", "/thing", None), ("POST", "/admin", Some("junk"))],
            );
            for x in &a {
                assert_eq!((x.status, x.body.as_str()), (200, "admin"));
            }
        }

        #[test]
        fn bearer_tokens_and_roles_are_enforced() {
            let t = tokens(&["read:r-tok", "write:w-tok", "admin:a-tok"]).unwrap();
            let a = exchange(
                app(t),
                &[
                    ("GET", "/thing", None),
                    ("GET", "/thing", Some("Basic cjp0")),
                    ("GET", "/thing", Some("Bearer")),
                    ("GET", "/thing", Some("Bearer nope")),
                    ("GET", "/thing", Some("Bearer r-tok")),
                    ("GET", "/thing", Some("bearer  r-tok")),
                    ("POST", "/thing", Some("Bearer r-tok")),
                    ("POST", "/thing", Some("Bearer w-tok")),
                    ("POST", "/admin", Some("Bearer w-tok")),
                    ("POST", "/admin", Some("Bearer a-tok")),
                    ("GET", "/elsewhere", None),
                ],
            );
            let got: Vec<(u16, &str)> = a.iter().map(|x| (x.status, x.body.as_str())).collect();
            assert_eq!(got[4], (200, "read"));
            assert_eq!(got[5], (200, "read"));
            assert_eq!(got[7], (200, "write"));
            assert_eq!(got[9], (200, "admin"));
            assert_eq!(got[10].0, 404, "unrouted paths are not guarded");
            for x in &a[0..4] {
                assert_eq!(x.status, 401);
                assert!(
                    x.challenge
                        .as_deref()
                        .is_some_and(|c| c.starts_with(r#"Bearer realm="winged""#)),
                    "{:?}",
                    x.challenge
                );
            }
            for (i, need, holds) in [(6, "write", "read"), (8, "admin", "write")] {
                let x = &a[i];
                assert_eq!(x.status, 403);
                assert_eq!(x.content_type.as_deref(), Some("application/problem+json"));
                let body: Value = serde_json::from_str(&x.body).unwrap();
                assert_eq!(body["type"], "urn:winged:problem:forbidden");
                let detail = body["detail"].as_str().unwrap();
                assert!(
                    detail.contains(&format!("needs the {need} role")),
                    "{detail}"
                );
                assert!(detail.contains(&format!("holds {holds}")), "{detail}");
            }
            let unknown: Value = serde_json::from_str(&a[3].body).unwrap();
            assert_eq!(unknown["status"], 401);
            assert_eq!(
                a[3].content_type.as_deref(),
                Some("application/problem+json")
            );
        }
    }
}
