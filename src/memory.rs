//! Memory estimates before large allocations: a fit or CV on
//! m rows holds several m × m matrices, and at m = 20 000 one is 3.2 GB.
//! Commands estimate what they will allocate, print it for large inputs and
//! refuse, naming an option that fits, when it exceeds the limit.
//!
//! The limit is `ROBOKRIGE_MEMORY_LIMIT` when set (bytes, or with a `K`,
//! `M`, `G` suffix, powers of 1024), else the operating system's available
//! memory (`MemAvailable` of `/proc/meminfo`), else none.

use crate::{Error, Result};

/// Environment variable overriding the memory limit.
pub const LIMIT_ENV: &str = "ROBOKRIGE_MEMORY_LIMIT";

/// Bytes of one dense m × m matrix of f64.
pub fn square_bytes(m: usize) -> u64 {
    (m as u64) * (m as u64) * 8
}

/// Parse `"8G"`, `"512M"`, `"1000000"`.
pub fn parse_size(s: &str) -> Option<u64> {
    let s = s.trim();
    let (num, mult) = match s.chars().last()? {
        'k' | 'K' => (&s[..s.len() - 1], 1u64 << 10),
        'm' | 'M' => (&s[..s.len() - 1], 1 << 20),
        'g' | 'G' => (&s[..s.len() - 1], 1 << 30),
        _ => (s, 1),
    };
    let v: f64 = num.trim().parse().ok()?;
    (v.is_finite() && v > 0.0).then_some((v * mult as f64) as u64)
}

/// The limit in force and where it comes from.
pub fn limit() -> Option<(u64, &'static str)> {
    if let Ok(v) = std::env::var(LIMIT_ENV) {
        return parse_size(&v).map(|b| (b, "ROBOKRIGE_MEMORY_LIMIT"));
    }
    available().map(|b| (b, "available memory"))
}

/// `MemAvailable` of `/proc/meminfo`, bytes.
pub fn available() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// A human size: `1.2 GB`.
pub fn human(bytes: u64) -> String {
    let b = bytes as f64;
    if b >= 1e9 {
        format!("{:.1} GB", b / 1e9)
    } else if b >= 1e6 {
        format!("{:.0} MB", b / 1e6)
    } else {
        format!("{:.0} kB", b / 1e3)
    }
}

/// Refuse `what` when it needs more than the limit; `hint` names what to
/// do instead (an option with fewer rows).
pub fn check(what: &str, needed: u64, hint: &str) -> Result<()> {
    match limit() {
        Some((lim, source)) if needed > lim => Err(Error::Memory {
            what: what.into(),
            needed: human(needed),
            limit: format!("{} ({source})", human(lim)),
            hint: hint.into(),
        }),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_with_suffixes() {
        assert_eq!(parse_size("8G"), Some(8 << 30));
        assert_eq!(parse_size("512m"), Some(512 << 20));
        assert_eq!(parse_size("1000"), Some(1000));
        assert_eq!(parse_size("x"), None);
        assert_eq!(parse_size("-1G"), None);
        assert_eq!(square_bytes(1000), 8_000_000);
    }
}
