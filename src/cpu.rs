//! The CPU check the command line and the Python module run before anything else.
//! `.cargo/config.toml` builds for the CPU of the machine that builds it; the same binary (or
//! wheel) copied to a CPU without one of its instruction-set extensions would die of an
//! illegal instruction, with no word of why.
//!
//! std's `is_x86_feature_detected!` cannot tell: for an extension the binary was compiled to
//! use it answers yes without asking the CPU. So the CPU is asked here, by CPUID, for each
//! extension the compiler may use on its own in this code (vector, bit-manipulation and
//! crypto instructions). Each entry's bit is checked against std's runtime answer by a test.

/// A CPUID register (the extensions checked are all in eax, ebx or ecx).
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
enum Reg {
    Eax,
    Ebx,
    Ecx,
}

/// An instruction-set extension as `target_feature` names it, whether this binary was
/// compiled to use it, std's answer, and where CPUID reports it.
#[cfg(target_arch = "x86_64")]
struct Extension {
    name: &'static str,
    compiled: bool,
    /// std's `is_x86_feature_detected!`: the CPU's answer only when `compiled` is false.
    #[cfg(test)]
    std_says: fn() -> bool,
    leaf: u32,
    subleaf: u32,
    reg: Reg,
    bit: u32,
}

#[cfg(target_arch = "x86_64")]
macro_rules! extension {
    ($name:tt, $leaf:expr, $subleaf:expr, $reg:ident, $bit:expr) => {
        Extension {
            name: $name,
            compiled: cfg!(target_feature = $name),
            #[cfg(test)]
            std_says: || std::is_x86_feature_detected!($name),
            leaf: $leaf,
            subleaf: $subleaf,
            reg: Reg::$reg,
            bit: $bit,
        }
    };
}

/// The extensions checked, with their CPUID leaf, subleaf, register and bit (Intel SDM vol. 2,
/// CPUID; AMD APM vol. 3 for leaf 0x8000_0001).
#[cfg(target_arch = "x86_64")]
#[rustfmt::skip]
const EXTENSIONS: &[Extension] = &[
    extension!("sse3", 1, 0, Ecx, 0),
    extension!("pclmulqdq", 1, 0, Ecx, 1),
    extension!("ssse3", 1, 0, Ecx, 9),
    extension!("fma", 1, 0, Ecx, 12),
    extension!("sse4.1", 1, 0, Ecx, 19),
    extension!("sse4.2", 1, 0, Ecx, 20),
    extension!("movbe", 1, 0, Ecx, 22),
    extension!("popcnt", 1, 0, Ecx, 23),
    extension!("aes", 1, 0, Ecx, 25),
    extension!("avx", 1, 0, Ecx, 28),
    extension!("f16c", 1, 0, Ecx, 29),
    extension!("bmi1", 7, 0, Ebx, 3),
    extension!("avx2", 7, 0, Ebx, 5),
    extension!("bmi2", 7, 0, Ebx, 8),
    extension!("avx512f", 7, 0, Ebx, 16),
    extension!("avx512dq", 7, 0, Ebx, 17),
    extension!("adx", 7, 0, Ebx, 19),
    extension!("avx512ifma", 7, 0, Ebx, 21),
    extension!("avx512cd", 7, 0, Ebx, 28),
    extension!("sha", 7, 0, Ebx, 29),
    extension!("avx512bw", 7, 0, Ebx, 30),
    extension!("avx512vl", 7, 0, Ebx, 31),
    extension!("avx512vbmi", 7, 0, Ecx, 1),
    extension!("avx512vbmi2", 7, 0, Ecx, 6),
    extension!("gfni", 7, 0, Ecx, 8),
    extension!("vaes", 7, 0, Ecx, 9),
    extension!("vpclmulqdq", 7, 0, Ecx, 10),
    extension!("avx512vnni", 7, 0, Ecx, 11),
    extension!("avx512bitalg", 7, 0, Ecx, 12),
    extension!("avx512vpopcntdq", 7, 0, Ecx, 14),
    extension!("avx512bf16", 7, 1, Eax, 5),
    extension!("lzcnt", 0x8000_0001, 0, Ecx, 5),
];

/// Whether the CPU reports `e` (a leaf beyond the CPU's highest reports nothing).
#[cfg(target_arch = "x86_64")]
fn cpu_has(e: &Extension) -> bool {
    use std::arch::x86_64::__cpuid_count;
    let highest = __cpuid_count(e.leaf & 0x8000_0000, 0).eax;
    if e.leaf > highest {
        return false;
    }
    let r = __cpuid_count(e.leaf, e.subleaf);
    let word = match e.reg {
        Reg::Eax => r.eax,
        Reg::Ebx => r.ebx,
        Reg::Ecx => r.ecx,
    };
    word >> e.bit & 1 == 1
}

/// The first instruction-set extension this binary was compiled to use that this CPU lacks.
#[cfg(target_arch = "x86_64")]
pub fn missing_feature() -> Option<&'static str> {
    EXTENSIONS
        .iter()
        .find(|e| e.compiled && !cpu_has(e))
        .map(|e| e.name)
}

/// What comes before the missing extension's name in the refusal.
pub const REFUSAL_START: &str = "this appell was compiled for a CPU with the ";
/// What comes after it.
pub const REFUSAL_END: &str = " instructions, which this CPU lacks (.cargo/config.toml builds for the CPU of the machine that builds it): build it again on this machine, or a portable build anywhere with RUSTFLAGS=\"-C target-cpu=x86-64\"";

/// Say on stderr which extension is missing and how to build for this CPU. Plain writes: the
/// formatting machinery would copy its arguments through vector registers this CPU may lack
/// (checked under qemu's emulation of CPUs without AVX and without AVX-512).
#[inline(never)]
pub fn refuse(feature: &str) {
    use std::io::Write;
    let mut err = std::io::stderr();
    let _ = err.write_all(b"error: ");
    let _ = err.write_all(REFUSAL_START.as_bytes());
    let _ = err.write_all(feature.as_bytes());
    let _ = err.write_all(REFUSAL_END.as_bytes());
    let _ = err.write_all(b"\n");
}

/// Other architectures: nothing is checked.
#[cfg(not(target_arch = "x86_64"))]
pub fn missing_feature() -> Option<&'static str> {
    None
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;

    #[test]
    fn cpuid_answers_as_std_does_for_every_extension_checked() {
        for e in EXTENSIONS {
            if e.compiled {
                // Built for this CPU (the tests run where they are built): it has them all.
                assert!(cpu_has(e), "{} compiled in but not found", e.name);
            } else {
                // Not compiled in: std asks the CPU, and the two must agree.
                assert_eq!(cpu_has(e), (e.std_says)(), "{}", e.name);
            }
        }
        assert_eq!(missing_feature(), None);
    }
}
