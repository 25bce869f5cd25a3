//! Subnormal numbers: flushed to zero on every thread that computes, or kept (IEEE
//! gradual underflow) when asked.
//!
//! Owns [`Subnormals`] (the process's choice, [`set_ieee_subnormals`] /
//! `signorini --ieee-subnormals`), [`FlushGuard`] (the choice applied to the calling
//! thread and to every worker of rayon's global pool for the guard's life, the previous
//! state put back on drop) and [`apply_to_current_thread`] for the threads the driver
//! spawns itself (the history and frame writers) and the pools it builds.
//!
//! Why: a wave entering a long chain (the bar past a few thousand elements at small
//! steps) leaves values that decay geometrically ahead of its front; the chain solves
//! and the Delassus column updates then run on numbers below 2.2e-308, where many CPUs
//! take a micro-code assist per operation (Intel: about a hundred cycles; the AMD EPYC of
//! the development machine: about 1.2× on a chain recurrence, measured in C). Flushing
//! them (x86-64: MXCSR's FTZ and DAZ bits; aarch64: FPCR.FZ) changes a result only below
//! 2.2e-308 of its scale, far below every tolerance of the schemes, and is what a C loop
//! built with `-ffast-math` does. `--ieee-subnormals` keeps gradual underflow for a
//! bitwise comparison with a build or peer that keeps it.
//!
//! Written here rather than with the `no_denormals` crate: that crate scopes the flags to
//! one closure on one thread, and a run needs them on rayon's workers and on the
//! writer threads for its whole life; the register access is two instructions either way.

#![allow(unsafe_code)]

use std::sync::atomic::{AtomicBool, Ordering};

/// What the computing threads of a run do with subnormal numbers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Subnormals {
    /// Flushed to zero (results and operands): the default where the CPU allows it.
    Flushed,
    /// IEEE gradual underflow (`--ieee-subnormals`, or a CPU without the control).
    Ieee,
}

impl Subnormals {
    /// The name written to `summary.json` and checkpoints.
    pub fn name(self) -> &'static str {
        match self {
            Subnormals::Flushed => "flushed",
            Subnormals::Ieee => "ieee",
        }
    }
}

static IEEE: AtomicBool = AtomicBool::new(false);

/// Asks for IEEE gradual underflow (`true`) or the default flush (`false`) in runs
/// started from now on, process-wide (`signorini --ieee-subnormals`).
pub fn set_ieee_subnormals(on: bool) {
    IEEE.store(on, Ordering::Relaxed);
}

/// Whether this build can set the flush on this CPU (x86-64 and aarch64).
pub fn flush_supported() -> bool {
    cfg!(any(target_arch = "x86_64", target_arch = "aarch64"))
}

/// The subnormal mode runs started now use: [`Subnormals::Flushed`] where supported
/// unless [`set_ieee_subnormals`] asked otherwise.
pub fn subnormals() -> Subnormals {
    if !IEEE.load(Ordering::Relaxed) && flush_supported() {
        Subnormals::Flushed
    } else {
        Subnormals::Ieee
    }
}

#[cfg(target_arch = "x86_64")]
mod reg {
    /// MXCSR's flush-to-zero (bit 15) and denormals-are-zero (bit 6) bits.
    pub const FLUSH: u64 = (1 << 15) | (1 << 6);

    pub fn read() -> u64 {
        let mut c: u32 = 0;
        // SAFETY: `stmxcsr` stores the 32-bit control register to the valid,
        // aligned location given; it reads nothing else and changes no flag.
        unsafe {
            std::arch::asm!("stmxcsr [{}]", in(reg) &mut c, options(nostack, preserves_flags));
        }
        u64::from(c)
    }

    pub fn write(v: u64) {
        let c = v as u32;
        // SAFETY: `ldmxcsr` loads a value read from the same register with only the
        // FTZ and DAZ bits changed (both supported on every x86-64 CPU); the rounding
        // mode and exception masks stay as the compiler assumes them.
        unsafe {
            std::arch::asm!("ldmxcsr [{}]", in(reg) &c, options(nostack, readonly, preserves_flags));
        }
    }
}

#[cfg(target_arch = "aarch64")]
mod reg {
    /// FPCR's flush-to-zero bit (FZ, bit 24).
    pub const FLUSH: u64 = 1 << 24;

    pub fn read() -> u64 {
        let v: u64;
        // SAFETY: reading FPCR has no side effect.
        unsafe {
            std::arch::asm!("mrs {}, fpcr", out(reg) v, options(nomem, nostack, preserves_flags));
        }
        v
    }

    pub fn write(v: u64) {
        // SAFETY: writes back a value read from FPCR with only FZ changed; the
        // rounding mode stays as the compiler assumes it.
        unsafe {
            std::arch::asm!("msr fpcr, {}", in(reg) v, options(nomem, nostack, preserves_flags));
        }
    }
}

#[cfg(not(any(target_arch = "x86_64", target_arch = "aarch64")))]
mod reg {
    pub const FLUSH: u64 = 0;
    pub fn read() -> u64 {
        0
    }
    pub fn write(_: u64) {}
}

/// Sets `mode` on the calling thread; returns the thread's previous control word (to
/// give [`restore_current_thread`]).
pub fn apply_to_current_thread(mode: Subnormals) -> u64 {
    let old = reg::read();
    let new = match mode {
        Subnormals::Flushed => old | reg::FLUSH,
        Subnormals::Ieee => old & !reg::FLUSH,
    };
    if new != old {
        reg::write(new);
    }
    old
}

/// Puts back a control word [`apply_to_current_thread`] returned.
pub fn restore_current_thread(old: u64) {
    if reg::read() != old {
        reg::write(old);
    }
}

/// The mode the calling thread runs in now (read from the register).
pub fn current_thread() -> Subnormals {
    if reg::FLUSH != 0 && reg::read() & reg::FLUSH == reg::FLUSH {
        Subnormals::Flushed
    } else {
        Subnormals::Ieee
    }
}

/// A run's subnormal mode on the calling thread and on every worker of the current
/// rayon pool, for the guard's life. Dropping it puts back the calling thread's own
/// state (a Python session's thread keeps its IEEE arithmetic between runs); the pool's
/// workers keep the mode, so runs sharing a pool at the same time (a sweep's points, a
/// study's runs) never undo each other's flush: the mode is one per process
/// ([`set_ieee_subnormals`]).
#[must_use = "the mode lasts as long as the guard"]
pub struct FlushGuard {
    mode: Subnormals,
    caller: u64,
}

impl FlushGuard {
    /// Applies `mode` (normally [`subnormals`]) to the calling thread and to the
    /// workers of the current rayon pool (the global one outside `install`).
    pub fn enter(mode: Subnormals) -> Self {
        let caller = apply_to_current_thread(mode);
        rayon::broadcast(|_| {
            apply_to_current_thread(mode);
        });
        FlushGuard { mode, caller }
    }

    /// Applies the process's mode ([`subnormals`]).
    pub fn for_run() -> Self {
        Self::enter(subnormals())
    }

    /// [`FlushGuard::for_run`] on the calling thread alone, for a caller whose pool's
    /// workers a guard of this mode has set already (they keep it): the Python
    /// package's `step(n)` after its first call, where waking every worker cost 13 µs
    /// a call against a 7 µs step of the bar.
    pub fn for_caller() -> Self {
        let mode = subnormals();
        FlushGuard {
            mode,
            caller: apply_to_current_thread(mode),
        }
    }

    /// The mode this guard applies.
    pub fn mode(&self) -> Subnormals {
        self.mode
    }
}

impl Drop for FlushGuard {
    fn drop(&mut self) {
        restore_current_thread(self.caller);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The smallest normal double halved: a subnormal result under IEEE, zero when
    /// flushed. `black_box` keeps the compiler from folding it at build time.
    fn halve_min_positive() -> f64 {
        std::hint::black_box(f64::MIN_POSITIVE) * std::hint::black_box(0.5)
    }

    #[test]
    fn guard_flushes_caller_and_workers_and_restores() {
        if !flush_supported() {
            return;
        }
        // a test thread of its own: IEEE as every new thread of the process starts
        assert!(halve_min_positive() > 0.0, "IEEE by default");
        {
            let g = FlushGuard::enter(Subnormals::Flushed);
            assert_eq!(g.mode(), Subnormals::Flushed);
            assert_eq!(halve_min_positive(), 0.0);
            let on_workers = rayon::broadcast(|_| halve_min_positive());
            assert!(on_workers.iter().all(|&x| x == 0.0), "{on_workers:?}");
            {
                // a nested IEEE guard (a study's run asking for IEEE) and back
                let _i = FlushGuard::enter(Subnormals::Ieee);
                assert!(halve_min_positive() > 0.0);
            }
            assert_eq!(current_thread(), Subnormals::Flushed);
        }
        assert!(halve_min_positive() > 0.0, "the caller restored on drop");
        assert_eq!(current_thread(), Subnormals::Ieee);
        // `for_caller`: the process's mode on this thread alone, put back on drop
        if subnormals() == Subnormals::Flushed {
            let g = FlushGuard::for_caller();
            assert_eq!(g.mode(), Subnormals::Flushed);
            assert_eq!(halve_min_positive(), 0.0);
            drop(g);
            assert!(halve_min_positive() > 0.0, "the caller restored on drop");
        }
    }
}
