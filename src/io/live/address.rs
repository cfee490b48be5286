//! Where the live view listens: `HOST:PORT`, `:PORT` or `PORT` (on
//! 127.0.0.1). Port 0 asks the system for a free one.

use std::fmt;
use std::str::FromStr;

/// Foxglove's own default port, on this machine only.
pub const DEFAULT_LIVE_ADDRESS: &str = "127.0.0.1:8765";

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LiveAddress {
    pub host: String,
    pub port: u16,
}

impl Default for LiveAddress {
    fn default() -> Self {
        DEFAULT_LIVE_ADDRESS
            .parse()
            .expect("the default address parses")
    }
}

impl fmt::Display for LiveAddress {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.host.contains(':') {
            write!(f, "[{}]:{}", self.host, self.port)
        } else {
            write!(f, "{}:{}", self.host, self.port)
        }
    }
}

impl FromStr for LiveAddress {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        let bad = |why: &str| {
            format!(
                "`{text}`: {why}; expected HOST:PORT (such as 127.0.0.1:8765 or \
                 0.0.0.0:9000), :PORT or PORT, with PORT from 0 (any free port) to 65535"
            )
        };
        let text = text.trim();
        let (host, port) = match text.rsplit_once(':') {
            Some((host, port)) => (host, port),
            None => ("", text),
        };
        let host = host.trim_start_matches('[').trim_end_matches(']');
        let host = if host.is_empty() { "127.0.0.1" } else { host };
        if host.chars().any(|c| c.is_whitespace() || c == '/') {
            return Err(bad("the host is not a host name or IP address"));
        }
        let port = port
            .parse::<u16>()
            .map_err(|_| bad("the port is not a number from 0 to 65535"))?;
        Ok(LiveAddress {
            host: host.to_string(),
            port,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn addresses_parse_and_bad_ones_are_named() {
        let a: LiveAddress = "0.0.0.0:9000".parse().unwrap();
        assert_eq!((a.host.as_str(), a.port), ("0.0.0.0", 9000));
        assert_eq!(
            ":0".parse::<LiveAddress>().unwrap().to_string(),
            "127.0.0.1:0"
        );
        assert_eq!("8766".parse::<LiveAddress>().unwrap().port, 8766);
        assert_eq!(
            "[::1]:80".parse::<LiveAddress>().unwrap().to_string(),
            "[::1]:80"
        );
        assert_eq!(LiveAddress::default().to_string(), DEFAULT_LIVE_ADDRESS);
        for bad in [
            "localhost:http",
            "127.0.0.1:70000",
            "a b:1",
            "http://x:1",
            "",
        ] {
            let e = bad.parse::<LiveAddress>().unwrap_err();
            assert!(
                e.contains(&format!("`{bad}`")) && e.contains("HOST:PORT"),
                "{e}"
            );
        }
    }
}
