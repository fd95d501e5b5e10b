//! Thread setup for tracing: flush-to-zero (FTZ) and denormals-are-zero (DAZ)
//! on every thread that calls Embree, as Embree's documentation asks (it
//! avoids slow denormal arithmetic in traversal), and a rayon pool whose
//! workers set them on start.
//!
//! The flags are per-thread MXCSR bits on x86_64 and change Rust float
//! arithmetic on that thread too (denormals become 0). Elsewhere this is a
//! no-op.

use crate::{Error, Result};

/// MXCSR bit 15 (flush to zero) and bit 6 (denormals are zero).
#[cfg(target_arch = "x86_64")]
const FTZ_DAZ: u32 = (1 << 15) | (1 << 6);

/// Turns on FTZ and DAZ for the calling thread (x86_64; no-op elsewhere).
pub fn set_flush_denormals() {
    #[cfg(target_arch = "x86_64")]
    {
        let mut csr: u32 = 0;
        // SAFETY: `stmxcsr` stores the 32-bit MXCSR register to the valid,
        // aligned `csr`; `ldmxcsr` loads it back with only the FTZ and DAZ
        // bits added, which cannot raise an exception (SSE is baseline on x86_64).
        unsafe {
            std::arch::asm!("stmxcsr [{}]", in(reg) &mut csr, options(nostack, preserves_flags));
            csr |= FTZ_DAZ;
            std::arch::asm!("ldmxcsr [{}]", in(reg) &csr, options(nostack, preserves_flags, readonly));
        }
    }
}

/// Whether FTZ and DAZ are both on for the calling thread (always `true`
/// off x86_64, where [`set_flush_denormals`] does nothing).
pub fn flush_denormals_enabled() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        let mut csr: u32 = 0;
        // SAFETY: `stmxcsr` only stores MXCSR to the valid, aligned `csr`.
        unsafe {
            std::arch::asm!("stmxcsr [{}]", in(reg) &mut csr, options(nostack, preserves_flags));
        }
        csr & FTZ_DAZ == FTZ_DAZ
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        true
    }
}

/// Workers allowed per available core: oversubscription beyond this only
/// costs memory and start-up time (`--threads 100000` used to start threads
/// for minutes).
pub const MAX_THREADS_PER_CORE: usize = 4;

/// The most workers [`thread_pool`] starts: [`MAX_THREADS_PER_CORE`] times
/// the available parallelism.
pub fn max_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get()) * MAX_THREADS_PER_CORE
}

/// `n` when it is at most [`max_threads`]; else an error naming `name`.
fn within_max(name: &'static str, n: usize) -> Result<usize> {
    let max = max_threads();
    if n > max {
        return Err(Error::param(
            name,
            format!("{n} is more than {MAX_THREADS_PER_CORE} per available core (at most {max})"),
        ));
    }
    Ok(n)
}

/// The workers a pool of "0 threads" gets: `RAYON_NUM_THREADS` when it is
/// set to a positive count (rayon's own convention), else one per available
/// core.
///
/// # Errors
/// [`Error::InvalidParameter`] (`RAYON_NUM_THREADS`) above [`max_threads`]:
/// rayon would start them all (`RAYON_NUM_THREADS=100000` started a
/// hundred thousand spinning workers for a 100-photon trace).
pub fn default_threads() -> Result<usize> {
    let env = std::env::var("RAYON_NUM_THREADS").ok();
    // Rayon ignores a value that is not a positive integer; so do we.
    match env.as_deref().map(str::parse::<usize>) {
        Some(Ok(n)) if n > 0 => within_max("RAYON_NUM_THREADS", n),
        _ => Ok(std::thread::available_parallelism().map_or(1, |n| n.get())),
    }
}

/// A rayon pool of `threads` workers (0: [`default_threads`]) that each call
/// [`set_flush_denormals`] when they start. Run tracing inside
/// `pool.install(..)`.
///
/// # Errors
/// [`Error::InvalidParameter`] (`threads`) above [`max_threads`], or when the
/// OS refuses to start the threads; as [`default_threads`] for 0.
pub fn thread_pool(threads: usize) -> Result<rayon::ThreadPool> {
    let threads = if threads == 0 {
        default_threads()?
    } else {
        threads
    };
    within_max("threads", threads)?;
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .thread_name(|i| format!("apm-trace-{i}"))
        .start_handler(|_| set_flush_denormals())
        .build()
        .map_err(|e| Error::param("threads", format!("cannot start {threads} threads: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pool_workers_flush_denormals() {
        let pool = thread_pool(2).unwrap();
        assert_eq!(pool.current_num_threads(), 2);
        let all = pool.broadcast(|_| flush_denormals_enabled());
        assert!(all.into_iter().all(|on| on));
        // The flags really act: a denormal result is flushed (FTZ) and a
        // denormal input reads as zero (DAZ); on this thread neither happens.
        use std::hint::black_box;
        let ftz = || black_box(f32::MIN_POSITIVE) * black_box(0.25);
        let daz = || black_box(f32::MIN_POSITIVE / 4.0) + black_box(0.0);
        #[cfg(target_arch = "x86_64")]
        assert_eq!(pool.install(|| (ftz(), daz())), (0.0, 0.0));
        if !flush_denormals_enabled() {
            assert_eq!(
                (ftz(), daz()),
                (f32::MIN_POSITIVE / 4.0, f32::MIN_POSITIVE / 4.0)
            );
        }
    }
}
