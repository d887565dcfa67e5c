//! What the benchmarks share: running a child process and reading its own peak memory.

use std::process::Command;
use std::time::Instant;

/// Runs `cmd`; returns its exit code, its own peak RSS in bytes (wait4's rusage of that child, the
/// figure `/usr/bin/time -v` prints as "Maximum resident set size") and the wall time in seconds.
pub fn measure(mut cmd: Command) -> (Option<i32>, u64, f64) {
    let start = Instant::now();
    // Reaped by wait4 below (which also gives this child's own rusage), not by Child::wait.
    #[allow(clippy::zombie_processes)]
    let child = cmd.spawn().expect("run the child");
    let pid = child.id() as libc::pid_t;
    // SAFETY: wait4 only writes into the status and rusage we pass; the child is ours.
    let (status, maxrss_kib) = unsafe {
        let mut status: libc::c_int = 0;
        let mut ru: libc::rusage = std::mem::zeroed();
        libc::wait4(pid, &mut status, 0, &mut ru);
        (status, ru.ru_maxrss as u64)
    };
    let code = libc::WIFEXITED(status).then(|| libc::WEXITSTATUS(status));
    (code, maxrss_kib * 1024, start.elapsed().as_secs_f64())
}
