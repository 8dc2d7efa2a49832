//! Who may see the panel: anyone on loopback, or whoever has the token. The panel shows the
//! camera's view of the machine's table; another address without a token would show it to
//! the whole network.

use std::net::SocketAddr;

use crate::PanelError;

/// The panel's access rule: a token, or none (loopback only).
#[derive(Clone)]
pub(crate) struct Access {
    token: Option<Vec<u8>>,
}

impl std::fmt::Debug for Access {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // The token itself is never printed.
        f.debug_struct("Access").field("token", &self.token.as_ref().map(|_| "…")).finish()
    }
}

impl Access {
    /// The rule for serving on `listen` with `token`.
    ///
    /// # Errors
    /// [`PanelError::TokenRequired`] for an address other than loopback without a token;
    /// [`PanelError::BadToken`] for an empty token or one with characters other than
    /// `A–Z a–z 0–9 - . _ ~` (it travels in a URL unescaped).
    pub(crate) fn new(listen: SocketAddr, token: Option<&str>) -> Result<Access, PanelError> {
        if let Some(t) = token {
            let url_safe = |c: char| c.is_ascii_alphanumeric() || "-._~".contains(c);
            if t.is_empty() || t.len() > 256 || !t.chars().all(url_safe) {
                return Err(PanelError::BadToken);
            }
        }
        if token.is_none() && !listen.ip().is_loopback() {
            return Err(PanelError::TokenRequired { listen });
        }
        Ok(Access { token: token.map(|t| t.as_bytes().to_vec()) })
    }

    /// Whether a request that gave `given` (its `?token=` or header, `None` when neither) may
    /// see the panel. The comparison takes the same time whatever bytes differ.
    #[must_use]
    pub(crate) fn allows(&self, given: Option<&str>) -> bool {
        match &self.token {
            None => true,
            Some(token) => given.is_some_and(|g| same_bytes(token, g.as_bytes())),
        }
    }

    /// Whether a request naming `host` (its `Host` header, `None` when it has none) may see a
    /// panel without a token: only a loopback name or address. A web page elsewhere that
    /// points its own name at 127.0.0.1 (DNS rebinding) sends its own name, and is refused.
    #[must_use]
    pub(crate) fn allows_host(&self, host: Option<&str>) -> bool {
        if self.token.is_some() {
            return true;
        }
        let Some(host) = host else { return true };
        let name = match host.strip_prefix('[') {
            Some(rest) => rest.split(']').next().unwrap_or_default(),
            None => host.split(':').next().unwrap_or_default(),
        };
        name.eq_ignore_ascii_case("localhost") || name.parse::<std::net::IpAddr>().is_ok_and(|ip| ip.is_loopback())
    }
}

/// `a == b` in time that depends on the lengths only, not on where they differ.
fn same_bytes(a: &[u8], b: &[u8]) -> bool {
    let n = a.len().max(b.len());
    let mut diff = u8::from(a.len() != b.len());
    for i in 0..n {
        diff |= a.get(i).copied().unwrap_or(0) ^ b.get(i).copied().unwrap_or(0);
    }
    std::hint::black_box(diff) == 0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn addr(text: &str) -> SocketAddr {
        text.parse().expect("an address")
    }

    #[test]
    fn only_loopback_is_served_without_a_token() {
        assert!(Access::new(addr("127.0.0.1:8090"), None).is_ok());
        assert!(Access::new(addr("[::1]:8090"), None).is_ok());
        for other in ["0.0.0.0:8090", "192.168.1.5:80", "[::]:8090"] {
            assert!(matches!(Access::new(addr(other), None), Err(PanelError::TokenRequired { .. })), "{other}");
            assert!(Access::new(addr(other), Some("s3cret")).is_ok(), "{other}");
        }
    }

    #[test]
    fn a_token_must_be_url_safe_and_is_matched_exactly() {
        for bad in ["", "a b", "a&b", "a?b", "é"] {
            assert!(matches!(Access::new(addr("0.0.0.0:1"), Some(bad)), Err(PanelError::BadToken)), "{bad:?}");
        }
        let access = Access::new(addr("0.0.0.0:1"), Some("s3cret")).expect("access");
        assert!(access.allows(Some("s3cret")));
        for wrong in [None, Some(""), Some("s3cre"), Some("s3cret!"), Some("S3cret")] {
            assert!(!access.allows(wrong), "{wrong:?}");
        }
        assert!(Access::new(addr("127.0.0.1:1"), None).expect("open").allows(None));
    }

    #[test]
    fn without_a_token_only_a_loopback_host_is_served() {
        let open = Access::new(addr("127.0.0.1:8090"), None).expect("open");
        for host in [None, Some("127.0.0.1:8090"), Some("localhost:8090"), Some("LOCALHOST"), Some("[::1]:8090")] {
            assert!(open.allows_host(host), "{host:?}");
        }
        for host in [Some("evil.example:8090"), Some("192.168.1.5"), Some("[::2]:1"), Some(""), Some("localhost.evil")]
        {
            assert!(!open.allows_host(host), "{host:?}");
        }
        let with_token = Access::new(addr("0.0.0.0:8090"), Some("t")).expect("token");
        assert!(with_token.allows_host(Some("machine.local:8090")), "the token guards it");
    }
}
