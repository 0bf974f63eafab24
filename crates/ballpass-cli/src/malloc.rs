//! The allocator setting of the `ballpass` process (glibc only).
//!
//! glibc's `malloc` serves every block above its mmap threshold (128 KiB,
//! raised dynamically up to 32 MiB) with a fresh `mmap` and gives it back
//! with `munmap` on `free`; worker threads' arenas are also trimmed back to
//! the OS as blocks are freed. A campaign allocates the same few megabytes
//! per record (the file's bytes, the columns, the correlation and spectrum
//! buffers) on every worker thread, so each record paid again for the
//! kernel to map and zero those pages: measured with `perf stat` on the
//! simulated campaign (2026-11-21), about 1 200 page faults per record and a
//! fifth of the CPU time of `ballpass sweep`.
//!
//! [`keep_freed_memory`] raises both thresholds once at start-up, so freed
//! blocks stay in the process and are reused: in the same measurement the
//! page faults of the sweep fell from ~118 000 to ~8 000. The price is that the
//! process keeps its peak heap until it exits, which for a command-line run
//! is the same as before. Library users keep whatever allocator settings
//! their program has; only the `ballpass` binary does this.

/// Largest mmap threshold glibc accepts on 64-bit targets (its default
/// dynamic maximum, `4 MiB * sizeof(long)`).
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const MMAP_THRESHOLD: libc::c_int = 32 << 20;

/// Free memory at the top of a heap kept before trimming it back.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const TRIM_THRESHOLD: libc::c_int = 1 << 30;

/// Keeps freed heap memory in the process for reuse (see the module docs);
/// does nothing outside glibc.
#[allow(unsafe_code)]
pub fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: `mallopt` only changes malloc's tuning parameters; it is
    // called once at the start of `main`, before any other thread exists,
    // with parameter names and values glibc documents. A refused value
    // (return 0) leaves the default in place, which is only slower.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, MMAP_THRESHOLD);
        libc::mallopt(libc::M_TRIM_THRESHOLD, TRIM_THRESHOLD);
    }
}

/// Mmap threshold of [`return_freed_memory`]: every block from 1 MiB up
/// (a record-length buffer, a correlation block, a CSV piece) is mapped on
/// its own and unmapped when freed.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const RETURN_MMAP_THRESHOLD: libc::c_int = 1 << 20;

/// Free memory at the top of a heap trimmed back by [`return_freed_memory`].
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const RETURN_TRIM_THRESHOLD: libc::c_int = 4 << 20;

/// The opposite of [`keep_freed_memory`], for `analyze`: give freed
/// memory back to the OS at once, so that the peak resident memory is the
/// peak of what is in use. `analyze` reads few records, often long ones,
/// and frees each stage's record-length buffers before the next stage
/// (the analysis of a long record is staged to hold few of them at once);
/// memory kept for reuse would add the freed blocks of every worker
/// thread's heap to the peak: measured on a 2-hour record at 1 kHz,
/// 610 MB resident for 465 MB in use. Fixed thresholds also stop glibc
/// raising them as blocks are freed. Does nothing outside glibc.
#[allow(unsafe_code)]
pub fn return_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: as in `keep_freed_memory`: called once at the start of
    // `main`, before any other thread exists, with documented parameters;
    // a refused value leaves the default in place.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, RETURN_MMAP_THRESHOLD);
        libc::mallopt(libc::M_TRIM_THRESHOLD, RETURN_TRIM_THRESHOLD);
    }
}
