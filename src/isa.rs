//! Embree's kernel sets, and pinning one so that photons do not depend on the
//! CPU.
//!
//! Embree compiles its traversal and intersection kernels once per x86
//! instruction set (SSE2, SSE4.2, AVX, AVX2, AVX-512) and, by default, runs
//! the widest set the CPU has. The sets build different BVHs and intersect
//! with different float operations, so the same scene and seed give other
//! hits, hence other photons, on an AVX2 host than on an AVX-512 one.
//! Pinning the set (`isa=` in Embree's device configuration) removes that
//! dependence: the guarantee and its limits are in `docs/determinism.md`.
//!
//! Embree itself takes an unknown name such as `isa=avx512skx` silently and
//! runs SSE2, and runs a set the CPU lacks until an illegal instruction: the
//! names are checked here, and a set is pinned only where the CPU has it.

use std::fmt;
use std::str::FromStr;

use crate::{Error, Result};

/// The environment variable that pins the kernel set of every
/// `embree::Device::new` (and so of the command line,
/// when `--embree-isa` is not given), as `RAYON_NUM_THREADS` sets rayon's
/// threads.
pub const ISA_ENV: &str = "ADAPTIVE_PM_EMBREE_ISA";

/// One of Embree's x86 kernel sets, narrowest first.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Isa {
    /// SSE2, the x86-64 baseline.
    Sse2,
    /// SSE4.2 (with POPCNT).
    Sse42,
    /// AVX.
    Avx,
    /// AVX2 (with FMA, F16C, BMI1/2, LZCNT).
    Avx2,
    /// AVX-512 (F, DQ, CD, BW, VL: Embree's Skylake-X set).
    Avx512,
}

impl Isa {
    /// Every set, narrowest first.
    pub const ALL: [Isa; 5] = [Isa::Sse2, Isa::Sse42, Isa::Avx, Isa::Avx2, Isa::Avx512];

    /// The name Embree's `isa=` configuration takes.
    pub fn name(self) -> &'static str {
        match self {
            Isa::Sse2 => "sse2",
            Isa::Sse42 => "sse4.2",
            Isa::Avx => "avx",
            Isa::Avx2 => "avx2",
            Isa::Avx512 => "avx512",
        }
    }

    /// The code a photon file's header stores (0 there means "not recorded").
    pub fn code(self) -> u8 {
        self as u8 + 1
    }

    /// The set of a header code; `None` for 0 and unknown codes.
    pub fn from_code(code: u8) -> Option<Isa> {
        Isa::ALL.get(usize::from(code).checked_sub(1)?).copied()
    }

    /// Whether this CPU can run the set's kernels.
    pub fn is_supported(self) -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::is_x86_feature_detected as has;
            match self {
                Isa::Sse2 => true,
                Isa::Sse42 => has!("sse4.2") && has!("popcnt"),
                Isa::Avx => Isa::Sse42.is_supported() && has!("avx"),
                Isa::Avx2 => {
                    Isa::Avx.is_supported()
                        && has!("avx2")
                        && has!("fma")
                        && has!("f16c")
                        && has!("bmi1")
                        && has!("bmi2")
                        && has!("lzcnt")
                }
                Isa::Avx512 => {
                    Isa::Avx2.is_supported()
                        && has!("avx512f")
                        && has!("avx512dq")
                        && has!("avx512cd")
                        && has!("avx512bw")
                        && has!("avx512vl")
                }
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            false
        }
    }

    /// The widest set this CPU runs: the one Embree picks when none is
    /// pinned (Debian's and Intel's builds carry all five). `None` off x86-64.
    pub fn native() -> Option<Isa> {
        Isa::ALL.into_iter().rev().find(|isa| isa.is_supported())
    }

    /// The sets this CPU runs, narrowest first.
    pub fn supported() -> Vec<Isa> {
        Isa::ALL.into_iter().filter(|i| i.is_supported()).collect()
    }

    /// `self`, if this CPU runs it.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] (`embree isa`) naming the sets it does run.
    pub fn require_supported(self) -> Result<Isa> {
        if self.is_supported() {
            return Ok(self);
        }
        let have: Vec<&str> = Isa::supported().into_iter().map(Isa::name).collect();
        Err(Error::param(
            "embree isa",
            format!(
                "this CPU cannot run Embree's {self} kernels; it runs {}",
                if have.is_empty() {
                    "none of them".to_string()
                } else {
                    have.join(", ")
                }
            ),
        ))
    }

    /// The set named by [`ISA_ENV`], if the variable is set and not empty.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the variable, for a value that is
    /// not a set's name or not valid Unicode.
    pub fn from_env() -> Result<Option<Isa>> {
        match std::env::var(ISA_ENV) {
            Err(std::env::VarError::NotPresent) => Ok(None),
            Err(std::env::VarError::NotUnicode(v)) => Err(Error::param(
                ISA_ENV,
                format!("is not valid Unicode: {v:?}"),
            )),
            Ok(v) if v.trim().is_empty() => Ok(None),
            Ok(v) => v
                .parse()
                .map(Some)
                .map_err(|e: Error| Error::param(ISA_ENV, e.to_string())),
        }
    }
}

/// The variant of the C maths library's `sincosf`, `sin`, `cos`, `exp` and
/// `pow` that glibc runs on this host: it picks one by CPU when a program
/// starts (its FMA variant where the CPU has FMA and AVX2, the FMA4 one on
/// FMA4 CPUs, else the SSE2 one), and the variants differ in the last bit
/// for some inputs. The tracer's directions and the analysis go through
/// them, so a map is reproduced only where the variant is the same too.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MathVariant {
    /// glibc's SSE2 code.
    Sse2,
    /// glibc's FMA4 code (AMD Bulldozer to Excavator).
    Fma4,
    /// glibc's FMA code (every CPU with AVX2).
    Fma,
}

impl MathVariant {
    /// Every variant, in code order.
    pub const ALL: [MathVariant; 3] = [MathVariant::Sse2, MathVariant::Fma4, MathVariant::Fma];

    /// This host's variant, as glibc 2.36 selects it (`None` off x86-64).
    pub fn host() -> Option<MathVariant> {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::is_x86_feature_detected as has;
            Some(if has!("fma") && has!("avx2") {
                MathVariant::Fma
            } else if is_fma4() {
                MathVariant::Fma4
            } else {
                MathVariant::Sse2
            })
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            None
        }
    }

    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            MathVariant::Sse2 => "sse2",
            MathVariant::Fma4 => "fma4",
            MathVariant::Fma => "fma",
        }
    }

    /// The code a photon file's header stores (0: not recorded).
    pub fn code(self) -> u8 {
        self as u8 + 1
    }

    /// The variant of a header code; `None` for 0 and unknown codes.
    pub fn from_code(code: u8) -> Option<MathVariant> {
        MathVariant::ALL
            .get(usize::from(code).checked_sub(1)?)
            .copied()
    }
}

/// FMA4 (CPUID 0x80000001, ECX bit 16), which `is_x86_feature_detected!`
/// does not name.
#[cfg(target_arch = "x86_64")]
fn is_fma4() -> bool {
    use std::arch::x86_64::{__cpuid, __get_cpuid_max};
    // The extended leaf is read only where the CPU reports it.
    let (max_extended, _) = __get_cpuid_max(0x8000_0000);
    max_extended >= 0x8000_0001 && __cpuid(0x8000_0001).ecx & (1 << 16) != 0
}

impl serde::Serialize for MathVariant {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

/// The compiled code that found a ray caster's hits, when that code
/// depends on the CPU: Embree's version and the kernel set it ran.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Kernels {
    /// The kernel set.
    pub isa: Isa,
    /// The library's `(major, minor, patch)`: Embree 3 and 4 build other BVHs.
    pub version: (u32, u32, u32),
}

impl Kernels {
    /// The version as one number, `major * 10000 + minor * 100 + patch`
    /// (the header's form; 0 there means "not recorded").
    pub fn version_code(&self) -> u32 {
        let (a, b, c) = self.version;
        a.saturating_mul(10_000)
            .saturating_add(b.min(99) * 100)
            .saturating_add(c.min(99))
    }
}

impl serde::Serialize for Kernels {
    /// `{"isa": "avx2", "embree": "3.13.5"}`.
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let mut st = s.serialize_struct("Kernels", 2)?;
        st.serialize_field("isa", &self.isa)?;
        st.serialize_field("embree", &version_name(self.version_code()))?;
        st.end()
    }
}

/// A [`Kernels::version_code`] as `major.minor.patch`.
pub fn version_name(code: u32) -> String {
    format!("{}.{}.{}", code / 10_000, code / 100 % 100, code % 100)
}

impl fmt::Display for Isa {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Isa {
    type Err = Error;

    /// Embree's names (`sse2`, `sse4.2`, `avx`, `avx2`, `avx512`), any case;
    /// `sse42` and `avx-512` are taken too.
    fn from_str(s: &str) -> Result<Isa> {
        let key = s.trim().to_ascii_lowercase();
        let isa = match key.as_str() {
            "sse2" => Isa::Sse2,
            "sse4.2" | "sse42" => Isa::Sse42,
            "avx" => Isa::Avx,
            "avx2" => Isa::Avx2,
            "avx512" | "avx-512" => Isa::Avx512,
            _ => {
                return Err(Error::param(
                    "embree isa",
                    format!(
                        "unknown kernel set {s:?}; expected one of sse2, sse4.2, avx, avx2, avx512"
                    ),
                ))
            }
        };
        Ok(isa)
    }
}

impl serde::Serialize for Isa {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_codes_and_order_round_trip() {
        for isa in Isa::ALL {
            assert_eq!(isa.name().parse::<Isa>().unwrap(), isa);
            assert_eq!(isa.name().to_uppercase().parse::<Isa>().unwrap(), isa);
            assert_eq!(Isa::from_code(isa.code()), Some(isa));
        }
        assert_eq!(Isa::from_code(0), None);
        assert_eq!(Isa::from_code(6), None);
        assert!(Isa::Sse2 < Isa::Avx512);
        for bad in ["", "avx512skx", "neon", "sse4.1", "avx 2"] {
            let e = bad.parse::<Isa>().unwrap_err().to_string();
            assert!(
                e.contains("unknown kernel set") && e.contains("avx2"),
                "{e}"
            );
        }
    }

    #[test]
    fn the_native_set_is_the_widest_supported() {
        assert!(Isa::Sse2.is_supported() || !cfg!(target_arch = "x86_64"));
        let supported = Isa::supported();
        assert_eq!(Isa::native(), supported.last().copied());
        // The sets nest: each one the CPU runs, it runs every narrower one too.
        for w in Isa::ALL.windows(2) {
            assert!(!w[1].is_supported() || w[0].is_supported());
        }
        if let Some(missing) = Isa::ALL.into_iter().find(|i| !i.is_supported()) {
            let e = missing.require_supported().unwrap_err().to_string();
            assert!(e.contains("cannot run"), "{e}");
        }
    }
}
