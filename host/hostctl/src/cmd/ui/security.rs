//! Who may talk to `hostctl ui`: a page that changes a haptic device's stiffness is a
//! physical-safety surface, so every request is checked before it is served.
//!
//! Rules (in this order; a malformed request is `400 Bad Request`, any other failure
//! `403 Forbidden`, both with a one-line reason):
//! 0. **Form**: at most one `Host` header, and an origin-form request target (`/path?query`):
//!    an absolute URI (`GET http://evil.example/ HTTP/1.1`), an authority (`CONNECT`) or `*`
//!    is refused, so the `Host` checked below is the only name the request carries.
//! 1. **Host**: the `Host` header must name the address the server is bound to (`IP:PORT`, or
//!    `localhost:PORT` when bound to a loopback address). This defeats DNS rebinding: a foreign
//!    site whose name resolves to 127.0.0.1 still sends its own name as `Host`.
//! 2. **Origin**: when a browser sends `Origin` (every cross-site request and every WebSocket
//!    upgrade), it must be `http://` + an allowed host. A foreign page's requests are refused.
//! 3. **Token**: the per-run token (128 random bits from the OS, printed in the URL as
//!    `?token=…`, as Jupyter does) must be given, as the `token` query parameter or the
//!    `X-Stiffwall-Token` header, for the page itself, every API request and the WebSocket
//!    at `/ws`. Only the static assets (script and style, no state, no secrets) are served
//!    without it.
//!
//! Invariants: the token comparison takes the same time wherever the strings differ; nothing
//! here depends on the client's address (the bind address already limits who can connect).

use std::net::SocketAddr;

/// Header carrying the token for API requests (the page sends it; `?token=` also works).
pub const TOKEN_HEADER: &str = "x-stiffwall-token";

/// Length of the token in hexadecimal digits (128 bits).
pub const TOKEN_HEX_DIGITS: usize = 32;

/// A fresh per-run token from the operating system's random source.
///
/// # Errors
/// The OS random source failed.
pub fn new_token() -> anyhow::Result<String> {
    let mut bytes = [0u8; TOKEN_HEX_DIGITS / 2];
    getrandom::fill(&mut bytes)
        .map_err(|e| anyhow::anyhow!("reading the OS random source for the token: {e}"))?;
    Ok(bytes.iter().map(|b| format!("{b:02x}")).collect())
}

/// Why a request was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum Refusal {
    /// `Host` missing or not the bound address.
    #[error("Host {0:?} is not this server's address (DNS rebinding protection); open the URL hostctl ui printed")]
    Host(String),
    /// `Origin` from another site.
    #[error("Origin {0:?} is not this server's page; requests from other sites are refused")]
    Origin(String),
    /// No token, or a wrong one.
    #[error("missing or wrong token: open the URL hostctl ui printed (it ends in ?token=...)")]
    Token,
    /// More than one `Host` header.
    #[error("{0} Host headers: a request must carry exactly one")]
    HostCount(usize),
    /// A request target that is not a path.
    #[error(
        "request target {0:?} is not a path: only origin-form targets (/path?query) are served"
    )]
    Target(String),
}

impl Refusal {
    /// The HTTP status of the refusal: 400 for a malformed request, 403 otherwise.
    #[must_use]
    pub fn status(&self) -> u16 {
        match self {
            Self::HostCount(_) | Self::Target(_) => 400,
            Self::Host(_) | Self::Origin(_) | Self::Token => 403,
        }
    }
}

/// Rule 0: `hosts` `Host` headers and the request target `uri` (as parsed by the server).
///
/// # Errors
/// [`Refusal::HostCount`] for more than one `Host` (none is rule 1's refusal);
/// [`Refusal::Target`] for a target
/// with a scheme or an authority, or one that does not start with `/`.
pub fn check_form(hosts: usize, uri: &axum::http::Uri) -> Result<(), Refusal> {
    if hosts > 1 {
        return Err(Refusal::HostCount(hosts));
    }
    if uri.scheme().is_some() || uri.authority().is_some() || !uri.path().starts_with('/') {
        return Err(Refusal::Target(uri.to_string()));
    }
    Ok(())
}

/// The checks of one server run.
#[derive(Debug, Clone)]
pub struct Guard {
    token: String,
    hosts: Vec<String>,
}

impl Guard {
    /// The guard of a server bound to `bound` with `token`.
    #[must_use]
    pub fn new(bound: SocketAddr, token: String) -> Self {
        let mut hosts = vec![bound.to_string()];
        if bound.ip().is_loopback() {
            hosts.push(format!("localhost:{}", bound.port()));
        }
        Self { token, hosts }
    }

    /// The token.
    #[must_use]
    pub fn token(&self) -> &str {
        &self.token
    }

    /// Host names (with port) this server answers to.
    #[must_use]
    pub fn hosts(&self) -> &[String] {
        &self.hosts
    }

    /// Checks `Host` and `Origin` (rules 1 and 2).
    ///
    /// # Errors
    /// The first rule broken.
    pub fn check_site(&self, host: Option<&str>, origin: Option<&str>) -> Result<(), Refusal> {
        let host = host.unwrap_or("");
        if !self.hosts.iter().any(|h| h.eq_ignore_ascii_case(host)) {
            return Err(Refusal::Host(host.to_string()));
        }
        if let Some(o) = origin {
            let ok = o
                .strip_prefix("http://")
                .is_some_and(|rest| self.hosts.iter().any(|h| h.eq_ignore_ascii_case(rest)));
            if !ok {
                return Err(Refusal::Origin(o.to_string()));
            }
        }
        Ok(())
    }

    /// Checks the token given (rule 3).
    ///
    /// # Errors
    /// [`Refusal::Token`] when it is absent or differs.
    pub fn check_token(&self, given: Option<&str>) -> Result<(), Refusal> {
        match given {
            Some(t) if constant_time_eq(t.as_bytes(), self.token.as_bytes()) => Ok(()),
            _ => Err(Refusal::Token),
        }
    }

    /// All three rules.
    ///
    /// # Errors
    /// The first rule broken.
    pub fn check(
        &self,
        host: Option<&str>,
        origin: Option<&str>,
        token: Option<&str>,
    ) -> Result<(), Refusal> {
        self.check_site(host, origin)?;
        self.check_token(token)
    }
}

/// The `token` parameter of a query string (`a=1&token=abc`).
#[must_use]
pub fn token_from_query(query: Option<&str>) -> Option<&str> {
    query?
        .split('&')
        .find_map(|kv| kv.strip_prefix("token="))
        .filter(|t| !t.is_empty())
}

fn constant_time_eq(a: &[u8], b: &[u8]) -> bool {
    if a.len() != b.len() {
        return false;
    }
    a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn guard() -> Guard {
        Guard::new("127.0.0.1:8737".parse().unwrap(), "ab12".repeat(8))
    }

    #[test]
    fn tokens_are_fresh_and_long() {
        let a = new_token().unwrap();
        let b = new_token().unwrap();
        assert_eq!(a.len(), TOKEN_HEX_DIGITS);
        assert_ne!(a, b);
        assert!(a.chars().all(|c| c.is_ascii_hexdigit()));
    }

    #[test]
    fn host_must_be_the_bound_address() {
        let g = guard();
        let t = Some(g.token().to_string());
        let t = t.as_deref();
        assert_eq!(g.check(Some("127.0.0.1:8737"), None, t), Ok(()));
        assert_eq!(g.check(Some("localhost:8737"), None, t), Ok(()));
        for bad in ["evil.example:8737", "127.0.0.1:80", "127.0.0.1", ""] {
            assert_eq!(
                g.check(Some(bad), None, t),
                Err(Refusal::Host(bad.to_string()))
            );
        }
        assert!(g.check(None, None, t).is_err());
    }

    #[test]
    fn origin_must_be_this_page() {
        let g = guard();
        let t = Some(g.token().to_string());
        let t = t.as_deref();
        let h = Some("127.0.0.1:8737");
        assert_eq!(g.check(h, Some("http://127.0.0.1:8737"), t), Ok(()));
        assert_eq!(g.check(h, Some("http://localhost:8737"), t), Ok(()));
        for bad in [
            "http://evil.example",
            "https://127.0.0.1:8737",
            "http://127.0.0.1:8738",
            "null",
        ] {
            assert_eq!(
                g.check(h, Some(bad), t),
                Err(Refusal::Origin(bad.to_string()))
            );
        }
    }

    #[test]
    fn token_must_match_exactly() {
        let g = guard();
        let h = Some("127.0.0.1:8737");
        assert_eq!(g.check(h, None, None), Err(Refusal::Token));
        assert_eq!(g.check(h, None, Some("ab12")), Err(Refusal::Token));
        let mut wrong = g.token().to_string();
        wrong.replace_range(31..32, "0");
        assert_eq!(g.check(h, None, Some(&wrong)), Err(Refusal::Token));
    }

    #[test]
    fn only_one_host_and_origin_form_targets() {
        let uri = |s: &str| s.parse::<axum::http::Uri>().unwrap();
        assert_eq!(check_form(1, &uri("/ws?token=x")), Ok(()));
        assert_eq!(check_form(2, &uri("/")), Err(Refusal::HostCount(2)));
        assert_eq!(
            check_form(0, &uri("/")),
            Ok(()),
            "no Host: rule 1 refuses it (403)"
        );
        for bad in [
            "http://evil.example/",
            "http://127.0.0.1:8737/",
            "evil.example:80",
            "*",
        ] {
            let e = check_form(1, &uri(bad)).unwrap_err();
            assert!(matches!(e, Refusal::Target(_)), "{bad}: {e:?}");
            assert_eq!(e.status(), 400);
        }
        assert_eq!(Refusal::Token.status(), 403);
    }

    #[test]
    fn non_loopback_bind_has_no_localhost_alias() {
        let g = Guard::new("192.0.2.7:9000".parse().unwrap(), "x".into());
        assert_eq!(g.hosts(), ["192.0.2.7:9000"]);
    }

    #[test]
    fn query_token() {
        assert_eq!(token_from_query(Some("token=abc")), Some("abc"));
        assert_eq!(token_from_query(Some("x=1&token=abc&y=2")), Some("abc"));
        assert_eq!(token_from_query(Some("token=")), None);
        assert_eq!(token_from_query(Some("mytoken=abc")), None);
        assert_eq!(token_from_query(None), None);
    }
}
