//! Two clocks for the render thread's CPU costs: wall time, and the
//! thread's own CPU time (`CLOCK_THREAD_CPUTIME_ID`), which does not count
//! the time the scheduler gave its core to another thread. On a machine
//! with fewer cores than busy threads (a software rasteriser's pool and
//! the sector workers beside the render thread) the two differ, and only
//! the second measures the renderer's own work.

use std::time::Instant;

/// This thread's CPU time (user and system) in seconds; `None` where the
/// platform has no per-thread clock.
pub fn thread_cpu_s() -> Option<f64> {
    #[cfg(unix)]
    {
        let mut t = libc::timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: clock_gettime writes one timespec it is given; a failure
        // (non-zero return) leaves it untouched and is reported as None.
        let r = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
        (r == 0).then_some(t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9)
    }
    #[cfg(not(unix))]
    {
        None
    }
}

/// A span timed on both clocks.
#[derive(Clone, Copy, Debug)]
pub struct Stopwatch {
    wall: Instant,
    cpu: Option<f64>,
}

/// Milliseconds of a span on both clocks.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Span {
    /// Wall-clock milliseconds.
    pub wall_ms: f64,
    /// The thread's CPU milliseconds (the wall time where there is no thread clock).
    pub cpu_ms: f64,
}

impl Stopwatch {
    /// Starts timing now on both clocks.
    pub fn start() -> Self {
        Self {
            wall: Instant::now(),
            cpu: thread_cpu_s(),
        }
    }

    /// The span since [`Stopwatch::start`] on this thread.
    pub fn span(&self) -> Span {
        let wall_ms = self.wall.elapsed().as_secs_f64() * 1e3;
        let cpu_ms = match (self.cpu, thread_cpu_s()) {
            (Some(a), Some(b)) => (b - a) * 1e3,
            _ => wall_ms,
        };
        Span { wall_ms, cpu_ms }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_thread_clock_counts_work_and_not_sleep() {
        let w = Stopwatch::start();
        std::thread::sleep(std::time::Duration::from_millis(30));
        let slept = w.span();
        assert!(slept.wall_ms >= 30.0, "{slept:?}");
        // Asleep the thread uses (almost) no CPU: 30 ms of wall time, under 5 ms of CPU.
        assert!(slept.cpu_ms < 5.0, "{slept:?}");
        let w = Stopwatch::start();
        let mut x = 0u64;
        while w.span().wall_ms < 20.0 {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1);
        }
        std::hint::black_box(x);
        let busy = w.span();
        // Busy it uses CPU for most of its wall time (the scheduler may take some).
        assert!(
            busy.cpu_ms > 2.0 && busy.cpu_ms <= busy.wall_ms + 1.0,
            "{busy:?}"
        );
    }
}
