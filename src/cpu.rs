//! The CPU check the command line and the Python module run before anything else.
//! `.cargo/config.toml` builds for the CPU of the machine that builds it; the same binary (or
//! wheel) copied to a CPU without one of its instruction-set extensions would die of an
//! illegal instruction, with no word of why.
//!
//! std's `is_x86_feature_detected!` cannot tell: for an extension the binary was compiled to
//! use it answers yes without asking the CPU. So the CPU is asked here, by CPUID, for each
//! extension the compiler may use on its own in this code (vector, bit-manipulation and
//! crypto instructions). Each entry's bit is checked against std's runtime answer by a test.

/// The CPUID leaves the extensions checked are in.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
enum Leaf {
    /// Leaf 1.
    Basic,
    /// Leaf 7, subleaf 0.
    Structured,
    /// Leaf 7, subleaf 1.
    Structured1,
    /// Leaf 0x8000_0001.
    Extended,
}

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
    leaf: Leaf,
    reg: Reg,
    bit: u32,
}

#[cfg(target_arch = "x86_64")]
macro_rules! extension {
    ($name:tt, $leaf:ident, $reg:ident, $bit:expr) => {
        Extension {
            name: $name,
            compiled: cfg!(target_feature = $name),
            #[cfg(test)]
            std_says: || std::is_x86_feature_detected!($name),
            leaf: Leaf::$leaf,
            reg: Reg::$reg,
            bit: $bit,
        }
    };
}

/// The extensions checked, with their CPUID leaf, register and bit (Intel SDM vol. 2,
/// CPUID; AMD APM vol. 3 for leaf 0x8000_0001).
#[cfg(target_arch = "x86_64")]
#[rustfmt::skip]
const EXTENSIONS: &[Extension] = &[
    extension!("sse3", Basic, Ecx, 0),
    extension!("pclmulqdq", Basic, Ecx, 1),
    extension!("ssse3", Basic, Ecx, 9),
    extension!("fma", Basic, Ecx, 12),
    extension!("sse4.1", Basic, Ecx, 19),
    extension!("sse4.2", Basic, Ecx, 20),
    extension!("movbe", Basic, Ecx, 22),
    extension!("popcnt", Basic, Ecx, 23),
    extension!("aes", Basic, Ecx, 25),
    extension!("avx", Basic, Ecx, 28),
    extension!("f16c", Basic, Ecx, 29),
    extension!("bmi1", Structured, Ebx, 3),
    extension!("avx2", Structured, Ebx, 5),
    extension!("bmi2", Structured, Ebx, 8),
    extension!("avx512f", Structured, Ebx, 16),
    extension!("avx512dq", Structured, Ebx, 17),
    extension!("adx", Structured, Ebx, 19),
    extension!("avx512ifma", Structured, Ebx, 21),
    extension!("avx512cd", Structured, Ebx, 28),
    extension!("sha", Structured, Ebx, 29),
    extension!("avx512bw", Structured, Ebx, 30),
    extension!("avx512vl", Structured, Ebx, 31),
    extension!("avx512vbmi", Structured, Ecx, 1),
    extension!("avx512vbmi2", Structured, Ecx, 6),
    extension!("gfni", Structured, Ecx, 8),
    extension!("vaes", Structured, Ecx, 9),
    extension!("vpclmulqdq", Structured, Ecx, 10),
    extension!("avx512vnni", Structured, Ecx, 11),
    extension!("avx512bitalg", Structured, Ecx, 12),
    extension!("avx512vpopcntdq", Structured, Ecx, 14),
    extension!("avx512bf16", Structured1, Eax, 5),
    extension!("lzcnt", Extended, Ecx, 5),
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

    /// Whether the CPU reports `e`.
    fn has(&self, e: &Extension) -> bool {
        let words = match e.leaf {
            Leaf::Basic => &self.basic,
            Leaf::Structured => &self.structured,
            Leaf::Structured1 => &self.structured_1,
            Leaf::Extended => &self.extended,
        };
        words[e.reg as usize] >> e.bit & 1 == 1
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
