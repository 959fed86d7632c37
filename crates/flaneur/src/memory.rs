//! The memory the system can give new allocations without swapping: the kernel's
//! `MemAvailable` estimate. Options that size large buffers (a client page cache, a
//! build's visibility tables) are held to it before anything is allocated, so that an
//! absurd value is refused by name rather than aborting the process on an allocation.

/// Bytes available to new allocations, where the system says (`/proc/meminfo`); `None`
/// where it cannot be read or lacks the figure.
pub(crate) fn available() -> Option<u64> {
    parse(&std::fs::read_to_string("/proc/meminfo").ok()?)
}

/// `MemAvailable:   123456 kB` → bytes.
fn parse(meminfo: &str) -> Option<u64> {
    let line = meminfo
        .lines()
        .find_map(|l| l.strip_prefix("MemAvailable:"))?;
    let kib: u64 = line.trim().strip_suffix("kB")?.trim().parse().ok()?;
    kib.checked_mul(1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mem_available_is_read_from_meminfo() {
        let text = "MemTotal:       24683520 kB\nMemFree:        22862048 kB\nMemAvailable:   24076288 kB\n";
        assert_eq!(parse(text), Some(24_076_288 * 1024));
        assert_eq!(parse("MemTotal: 5 kB\n"), None);
        assert_eq!(parse("MemAvailable: lots\n"), None);
    }

    #[test]
    fn memory_available_is_read_where_the_system_says() {
        if std::path::Path::new("/proc/meminfo").exists() {
            assert!(available().is_some_and(|b| b > 0));
        }
    }
}
