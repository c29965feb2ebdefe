//! The CPU time of the calling thread: what a replan costs, whatever else the machine runs.

/// Seconds of CPU time the calling thread has used (`CLOCK_THREAD_CPUTIME_ID`); `None` where
/// the platform has no such clock.
///
/// A replan's wall-clock latency includes the time the thread waited for a core; on a busy
/// machine that dominates the tail. The difference of two readings of this clock around a
/// replan is the work the replan itself did.
///
/// ```
/// let a = skyplan_replan::thread_cpu_s();
/// let mut x = 0u64;
/// for i in 0..1_000_000u64 { x = x.wrapping_add(i * i); }
/// std::hint::black_box(x);
/// if let (Some(a), Some(b)) = (a, skyplan_replan::thread_cpu_s()) {
///     assert!(b >= a);
/// }
/// ```
#[cfg(any(target_os = "linux", target_os = "macos"))]
#[allow(unsafe_code)]
pub fn thread_cpu_s() -> Option<f64> {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec that outlives the call; clock_gettime only
    // writes to it and reports failure through its return value.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    (rc == 0).then_some(ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9)
}

/// Seconds of CPU time the calling thread has used; `None`: no such clock on this platform.
#[cfg(not(any(target_os = "linux", target_os = "macos")))]
pub fn thread_cpu_s() -> Option<f64> {
    None
}
