//! The processor check at start-up: a build for x86-64-v3 (`.cargo/config.toml`) needs AVX2,
//! and on a processor without it the first such instruction would kill the process with an
//! illegal instruction. Read with `cpuid` and `xgetbv` (not `is_x86_feature_detected!`,
//! which a build for AVX2 answers `true` at compile time).

/// `Err` with the fix when the build needs AVX2 and this processor (or its operating system)
/// does not provide it.
pub fn check() -> Result<(), String> {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
    if !has_avx2() {
        return Err("this build of stickslip targets x86-64-v3 (AVX2, .cargo/config.toml) and this processor has \
                    no AVX2: rebuild with RUSTFLAGS=\"-C target-cpu=x86-64\""
            .to_string());
    }
    Ok(())
}

/// AVX2 (`cpuid` leaf 7, `ebx` bit 5) with the AVX state enabled by the operating system
/// (`cpuid` leaf 1, `ecx` bit 27 OSXSAVE, then `XCR0` bits 1 and 2).
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
fn has_avx2() -> bool {
    use std::arch::x86_64::{__cpuid, __cpuid_count, _xgetbv};
    // SAFETY: `cpuid` exists on every x86-64 processor; `xgetbv` is executed only when
    // OSXSAVE says the operating system enabled it.
    unsafe {
        if __cpuid(0).eax < 7 || __cpuid(1).ecx & (1 << 27) == 0 || _xgetbv(0) & 0b110 != 0b110 {
            return false;
        }
        __cpuid_count(7, 0).ebx & (1 << 5) != 0
    }
}

#[cfg(test)]
mod tests {
    /// The machine that runs the tests runs this build, so it passes the check.
    #[test]
    fn this_machine_passes() {
        assert_eq!(super::check(), Ok(()));
    }
}
