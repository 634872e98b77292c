//! The memory budget: every input that allocates in proportion to a number
//! it gives (mesh segments, height-field resolution, image dimensions, card
//! counts, frame size) is charged against it before the allocation, so a
//! large request is an error that names the input instead of an abort.
//! Estimates and their measurements: `docs/reliability.md`.

use std::fmt;

/// Environment variable that sets the budget (`himal --memory-budget` wins).
pub const MEMORY_BUDGET_ENV: &str = "HIMAL_MEMORY_BUDGET";

/// Resident bytes one mesh vertex costs from generation to upload: the CPU
/// `Vertex` (88 bytes), its GPU copy (host memory on lavapipe) and the
/// transient build copies. Measured: a 4,096-segment plane (16.8 M
/// vertices, 101 M indices) peaked 4.55 GB above the empty scene, 2.6 times
/// its 1.74 GB of vertex and index data; charged at 3 times.
pub const MESH_BYTES_PER_VERTEX: u64 = 3 * 88;
/// Resident bytes per index (3 times 4 bytes, as above).
pub const MESH_BYTES_PER_INDEX: u64 = 3 * 4;
/// Resident bytes per output pixel of the frame's targets (G-buffer,
/// lighting, AO, history rings, post chain). Measured with `himal soak`:
/// the renderer's GPU allocations grow 99 bytes per pixel from 64x64 to
/// 512x512 and resident memory 143; charged at 160.
pub const FRAME_BYTES_PER_PIXEL: u64 = 160;

/// A size in bytes: `4GiB`, `512MiB`, `1.5MB`, `100000` (a unit of B, KiB,
/// MiB, GiB, TiB, KB, MB, GB or TB, case-insensitive; none is bytes).
pub fn parse_bytes(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let scale: f64 = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 1.0,
        "k" | "kb" => 1e3,
        "kib" => 1024.0,
        "m" | "mb" => 1e6,
        "mib" => 1024.0 * 1024.0,
        "g" | "gb" => 1e9,
        "gib" => 1024.0 * 1024.0 * 1024.0,
        "t" | "tb" => 1e12,
        "tib" => 1024f64.powi(4),
        other => {
            return Err(format!(
                "unknown unit \"{other}\" (use B, KiB, MiB, GiB, TiB, KB, MB, GB or TB)"
            ));
        }
    };
    let n: f64 = number
        .parse()
        .map_err(|_| "expected a size such as 4GiB or 512MiB".to_string())?;
    let bytes = n * scale;
    // Past 1e18 an f64 no longer converts to u64 without saturating.
    if !(bytes.is_finite() && bytes <= 1e18) {
        return Err("must be at most 1000000TB".into());
    }
    Ok(bytes as u64)
}

/// How many bytes the scene and frame may plan to hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryBudget {
    /// The limit in bytes.
    pub bytes: u64,
}

impl Default for MemoryBudget {
    /// Half of the machine's memory (`/proc/meminfo`), else 4 GiB.
    fn default() -> Self {
        let total = std::fs::read_to_string("/proc/meminfo").ok().and_then(|s| {
            let line = s.lines().find(|l| l.starts_with("MemTotal:"))?;
            let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
            Some(kb * 1024)
        });
        Self {
            bytes: total.map_or(4 << 30, |t| t / 2),
        }
    }
}

impl MemoryBudget {
    /// `HIMAL_MEMORY_BUDGET` when set, else the machine default.
    pub fn from_env() -> Result<Self, String> {
        match std::env::var(MEMORY_BUDGET_ENV) {
            Ok(s) if !s.is_empty() => {
                Self::parse(&s).map_err(|e| format!("{MEMORY_BUDGET_ENV}={s}: {e}"))
            }
            _ => Ok(Self::default()),
        }
    }

    /// `4GiB`, `512MiB`, `2GB`, `100000` (bytes); at least 1 MiB.
    pub fn parse(s: &str) -> Result<Self, String> {
        let bytes = parse_bytes(s)?;
        if !(1 << 20..=1_000_000_000_000_000_000).contains(&bytes) {
            return Err("must lie between 1MiB and 1000000TB".into());
        }
        Ok(Self { bytes })
    }

    /// An error when `bytes` for `what` exceed the budget.
    pub fn check(&self, what: impl fmt::Display, bytes: u64) -> Result<(), String> {
        if bytes > self.bytes {
            return Err(format!(
                "{what} needs about {} of memory, above the memory budget of {} \
                 (--memory-budget or {MEMORY_BUDGET_ENV}; default half of this machine's memory)",
                Bytes(bytes),
                Bytes(self.bytes)
            ));
        }
        Ok(())
    }

    /// The resident bytes of a mesh with `vertices` and `indices`.
    pub fn mesh_bytes(vertices: u64, indices: u64) -> u64 {
        vertices
            .saturating_mul(MESH_BYTES_PER_VERTEX)
            .saturating_add(indices.saturating_mul(MESH_BYTES_PER_INDEX))
    }
}

/// Bytes in binary units, for messages.
pub struct Bytes(pub u64);

impl fmt::Display for Bytes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let b = self.0 as f64;
        const UNITS: [&str; 5] = ["B", "KiB", "MiB", "GiB", "TiB"];
        let mut v = b;
        let mut u = 0;
        while v >= 1024.0 && u + 1 < UNITS.len() {
            v /= 1024.0;
            u += 1;
        }
        if u == 0 {
            write!(f, "{} B", self.0)
        } else {
            write!(f, "{v:.1} {}", UNITS[u])
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_units_and_rejects_nonsense() {
        assert_eq!(MemoryBudget::parse("4GiB").unwrap().bytes, 4 << 30);
        assert_eq!(MemoryBudget::parse("512 MiB").unwrap().bytes, 512 << 20);
        assert_eq!(MemoryBudget::parse("2GB").unwrap().bytes, 2_000_000_000);
        assert_eq!(MemoryBudget::parse("1.5gib").unwrap().bytes, 3 << 29);
        for bad in ["", "0", "-1", "lots", "1e30GiB", "12XB", "1KiB", "nan"] {
            assert!(MemoryBudget::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn check_names_what_and_both_sizes() {
        let b = MemoryBudget { bytes: 1 << 30 };
        assert!(b.check("x", 1 << 30).is_ok());
        let e = b
            .check("plane \"p\" with 4096 segments", 3 << 30)
            .unwrap_err();
        assert!(e.contains("4096 segments") && e.contains("3.0 GiB") && e.contains("1.0 GiB"));
    }
}
