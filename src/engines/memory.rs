//! How much memory the machine can give, so that a run or a read that
//! needs more is refused with a clear message instead of aborting on
//! allocation.

/// Bytes of memory available now (Linux: MemAvailable of /proc/meminfo;
/// None where it cannot be read).
pub fn available_bytes() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    parse_meminfo(&text)
}

fn parse_meminfo(text: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Refuses `needed` bytes when more than `available` (when known), naming
/// `what`, both sizes and `override_hint`.
pub fn check(
    needed: u64,
    available: Option<u64>,
    what: &str,
    override_hint: &str,
) -> Result<(), String> {
    match available {
        Some(a) if needed > a => Err(format!(
            "{what} needs about {} of memory and this machine has {} available; \
             make the scene smaller, or {override_hint}",
            human(needed),
            human(a)
        )),
        _ => Ok(()),
    }
}

/// Bytes as MiB or GiB.
pub fn human(bytes: u64) -> String {
    let b = bytes as f64;
    if b >= (1u64 << 30) as f64 {
        format!("{:.1} GiB", b / (1u64 << 30) as f64)
    } else {
        format!("{:.1} MiB", b / (1u64 << 20) as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn meminfo_is_read_and_needs_are_compared() {
        let text = "MemTotal:       24000000 kB\nMemAvailable:   20000000 kB\n";
        assert_eq!(parse_meminfo(text), Some(20_000_000 * 1024));
        assert_eq!(parse_meminfo("MemTotal: 1 kB\n"), None);
        assert!(check(1 << 20, Some(1 << 30), "x", "y").is_ok());
        let err = check(
            213 << 30,
            Some(20 << 30),
            "the run",
            "pass --no-memory-check",
        )
        .unwrap_err();
        assert!(
            err.contains("213.0 GiB") && err.contains("20.0 GiB"),
            "{err}"
        );
        assert!(check(u64::MAX, None, "x", "y").is_ok());
    }
}
