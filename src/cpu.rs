//! The CPU check the command line and the Python module run before anything else.
//! `.cargo/config.toml` builds for the CPU of the machine that builds it; the same binary (or
//! wheel) copied to a CPU without one of its instruction-set extensions would die of an
//! illegal instruction, with no word of why.
//!
//! std's `is_x86_feature_detected!` cannot tell: for an extension the binary was compiled to
//! use it answers yes without asking the CPU. So the CPU is asked here, by CPUID, for each
//! extension the compiler may use on its own in this code (vector, bit-manipulation and
//! crypto instructions). Each entry's bit is checked against std's runtime answer by a test.

/// A CPUID register (the extensions checked are all in eax, ebx or ecx), as an index into
/// [`Leaves`]' words.
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

/// CPUID's words (eax, ebx, ecx) for the four leaves the extensions are in, each asked once:
/// in a virtual machine every CPUID traps to the hypervisor (4-6 us on the project machine),
/// and asking twice per extension had taken 0.25 ms of every run.
#[cfg(target_arch = "x86_64")]
struct Leaves {
    basic: [u32; 3],
    structured: [u32; 3],
    structured_1: [u32; 3],
    extended: [u32; 3],
}

#[cfg(target_arch = "x86_64")]
impl Leaves {
    fn ask() -> Leaves {
        use std::arch::x86_64::__cpuid_count;
        let highest_basic = __cpuid_count(0, 0).eax;
        let highest_extended = __cpuid_count(0x8000_0000, 0).eax;
        // A leaf beyond the CPU's highest reports nothing.
        let ask = |leaf: u32, subleaf: u32| {
            let highest = if leaf >= 0x8000_0000 {
                highest_extended
            } else {
                highest_basic
            };
            if leaf > highest {
                return [0; 3];
            }
            let r = __cpuid_count(leaf, subleaf);
            [r.eax, r.ebx, r.ecx]
        };
        Leaves {
            basic: ask(1, 0),
            structured: ask(7, 0),
            structured_1: ask(7, 1),
            extended: ask(0x8000_0001, 0),
        }
    }

    /// The words of `e`'s leaf (None for a leaf not asked: a test keeps every entry to these).
    fn of(&self, e: &Extension) -> Option<&[u32; 3]> {
        match (e.leaf, e.subleaf) {
            (1, 0) => Some(&self.basic),
            (7, 0) => Some(&self.structured),
            (7, 1) => Some(&self.structured_1),
            (0x8000_0001, 0) => Some(&self.extended),
            _ => None,
        }
    }

    /// Whether the CPU reports `e`.
    fn has(&self, e: &Extension) -> bool {
        self.of(e)
            .is_some_and(|w| w[e.reg as usize] >> e.bit & 1 == 1)
    }
}

/// The first instruction-set extension this binary was compiled to use that this CPU lacks.
#[cfg(target_arch = "x86_64")]
pub fn missing_feature() -> Option<&'static str> {
    let leaves = Leaves::ask();
    EXTENSIONS
        .iter()
        .find(|e| e.compiled && !leaves.has(e))
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
        let leaves = Leaves::ask();
        for e in EXTENSIONS {
            assert!(leaves.of(e).is_some(), "{}: leaf not asked", e.name);
            if e.compiled {
                // Built for this CPU (the tests run where they are built): it has them all.
                assert!(leaves.has(e), "{} compiled in but not found", e.name);
            } else {
                // Not compiled in: std asks the CPU, and the two must agree.
                assert_eq!(leaves.has(e), (e.std_says)(), "{}", e.name);
            }
        }
        assert_eq!(missing_feature(), None);
    }
}
