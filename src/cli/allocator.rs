//! The process's one allocator setting: large blocks are mapped on their own and given back to the
//! system when freed.
//!
//! Why: glibc's malloc raises its mmap threshold each time a mapped block is freed (up to 32 MiB);
//! from then on blocks of that size come from the heap and the per-thread arenas, and freed ones stay
//! there. An evaluation allocates and frees signals of tens of megabytes from several threads, so the
//! process kept far more than it used: on the 2-hour bench recording (`cargo bench --bench throughput`), a peak RSS of 208 MiB
//! for a live heap of about 150 MB (heaptrack). A fixed threshold of 1 MiB keeps every large block
//! out of the arenas: the peak RSS falls to 141 MiB for about 3 % more time (`cargo bench --bench
//! throughput` prints both; `MALLOC_MMAP_THRESHOLD_` in the environment still overrides it). Other
//! allocators (musl, macOS) have no such threshold, and nothing is changed there.

/// Blocks at or above this size are mapped on their own.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const MMAP_THRESHOLD: libc::c_int = 1 << 20;

/// Sets the threshold (glibc only), unless the user set one in the environment
/// (`MALLOC_MMAP_THRESHOLD_`, or `glibc.malloc.mmap_threshold` in `GLIBC_TUNABLES`) or asked for
/// glibc's own dynamic threshold with `TRAJDRIFT_MALLOC_DYNAMIC=1` (the throughput bench compares
/// both).
pub fn return_large_blocks() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    if std::env::var_os("MALLOC_MMAP_THRESHOLD_").is_none()
        && !std::env::var("GLIBC_TUNABLES").is_ok_and(|t| t.contains("glibc.malloc.mmap_threshold"))
        && std::env::var("TRAJDRIFT_MALLOC_DYNAMIC").as_deref() != Ok("1")
    {
        // SAFETY: mallopt only sets a tuning parameter of the allocator; it is called once, before
        // any other thread exists.
        unsafe {
            libc::mallopt(libc::M_MMAP_THRESHOLD, MMAP_THRESHOLD);
        }
    }
}
