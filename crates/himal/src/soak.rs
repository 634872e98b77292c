//! Memory over time (issue #16): the process's resident memory and a
//! least-squares slope over samples, for `himal soak` and the soak test.

/// Resident memory of this process in bytes (Linux: `/proc/self/statm`;
/// `None` elsewhere or when it cannot be read).
pub fn resident_bytes() -> Option<u64> {
    let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: u64 = statm.split_whitespace().nth(1)?.parse().ok()?;
    // statm counts pages of the kernel's page size; 4 KiB on every target we run.
    Some(pages * 4096)
}

/// One sample of a soak: the frame just drawn and the memory then.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SoakSample {
    /// Number of the frame just drawn (the x axis of the leak slope).
    pub frame: u64,
    /// Process resident memory (bytes); 0 where unknown.
    pub resident: u64,
    /// What the renderer holds on the GPU (scene, pool, history), bytes.
    pub gpu: u64,
}

/// Least-squares slope of `value(sample)` per frame over `samples`
/// (bytes per frame); 0 for fewer than two samples.
pub fn slope(samples: &[SoakSample], value: impl Fn(&SoakSample) -> u64) -> f64 {
    let n = samples.len() as f64;
    if samples.len() < 2 {
        return 0.0;
    }
    let mean_x = samples.iter().map(|s| s.frame as f64).sum::<f64>() / n;
    let mean_y = samples.iter().map(|s| value(s) as f64).sum::<f64>() / n;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for s in samples {
        let dx = s.frame as f64 - mean_x;
        sxy += dx * (value(s) as f64 - mean_y);
        sxx += dx * dx;
    }
    if sxx == 0.0 { 0.0 } else { sxy / sxx }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slope_of_a_line_and_of_a_flat_series() {
        let line: Vec<SoakSample> = (0..10)
            .map(|i| SoakSample {
                frame: i * 10,
                resident: 1000 + 50 * i * 10,
                gpu: 7,
            })
            .collect();
        assert!((slope(&line, |s| s.resident) - 50.0).abs() < 1e-9);
        assert_eq!(slope(&line, |s| s.gpu), 0.0);
        assert_eq!(slope(&line[..1], |s| s.resident), 0.0);
    }

    #[test]
    fn resident_memory_is_known_on_linux() {
        if cfg!(target_os = "linux") {
            assert!(resident_bytes().is_some_and(|b| b > 0));
        }
    }
}
