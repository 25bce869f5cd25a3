//! The arithmetic of the hand-written kernels: fused multiply-add where the CPU has it
//! (pulp's run-time dispatch), or the portable arithmetic that gives the same bits on
//! every CPU ([`set_portable_arithmetic`]).

/// The floating-point arithmetic of the chain recurrences (the tridiagonal solve).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Arithmetic {
    /// Fused multiply-add where the CPU has it: the fastest, but the last bits of a
    /// result depend on the CPU.
    Fused,
    /// Separate multiply and add everywhere: the same bits on every CPU (the golden
    /// histories of `tests/golden/` are this arithmetic's). faer's own kernels (the
    /// sparse Cholesky of solids) choose their instructions at run time in either mode.
    Portable,
}

impl Arithmetic {
    /// The name written to `summary.json` and checkpoints.
    pub fn name(self) -> &'static str {
        match self {
            Arithmetic::Fused => "fused",
            Arithmetic::Portable => "portable",
        }
    }
}

pub(super) static PORTABLE: std::sync::atomic::AtomicBool =
    std::sync::atomic::AtomicBool::new(false);

/// Asks for [`Arithmetic::Portable`] (`true`) or the default (`false`) in factorizations
/// made from now on, process-wide (`signorini --portable-arithmetic`).
pub fn set_portable_arithmetic(on: bool) {
    PORTABLE.store(on, std::sync::atomic::Ordering::Relaxed);
}

/// Whether this CPU has fused multiply-add.
pub fn cpu_has_fma() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::is_x86_feature_detected!("fma")
    }
    #[cfg(target_arch = "aarch64")]
    {
        true
    }
    #[cfg(not(any(target_arch = "x86_64", target_arch = "aarch64")))]
    {
        false
    }
}

/// The arithmetic factorizations made now use: [`Arithmetic::Fused`] where the CPU has
/// FMA unless [`set_portable_arithmetic`] asked otherwise.
pub fn arithmetic() -> Arithmetic {
    if !PORTABLE.load(std::sync::atomic::Ordering::Relaxed) && cpu_has_fma() {
        Arithmetic::Fused
    } else {
        Arithmetic::Portable
    }
}
