//! Finds the system Embree (4 preferred, 3 as fallback), compiles the C shim
//! against its header, generates bindings with bindgen and tells rustc what
//! to link.
//!
//! Search order, first hit wins:
//! 1. `EMBREE_DIR`: a prefix with `include/embree{4,3}/rtcore.h` and the
//!    library in `lib/` or `lib64/` (no fallback if it is set but wrong:
//!    the user asked for that one);
//! 2. `pkg-config` (`embree4`, then `embree3`) when a `.pc` file exists;
//! 3. the standard prefixes (`/usr`, `/usr/local`, Homebrew), Embree 4 first.
//!
//! Emits `cfg(embree4)` or `cfg(embree3)` and the metadata `version_major`,
//! `include` (seen by dependents' build scripts as `DEP_EMBREE_*`).
//!
//! Where Embree (or libclang) is missing the build fails with `cargo::error`
//! lines saying what to install, not with a panic. Under docs.rs (`DOCS_RS`
//! set) nothing is searched, compiled or linked: the documentation is built
//! from `src/docs_rs_bindings.rs`, bindings generated here from Embree 3.13.5.

use std::env;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A usable Embree installation.
struct Embree {
    /// 3 or 4.
    major: u32,
    /// The directory holding `embreeN/rtcore.h`.
    include_dir: PathBuf,
    /// Where `libembreeN` lives (`None`: let the linker search its defaults).
    lib_dir: Option<PathBuf>,
    /// How it was found, for the build log.
    source: String,
}

impl Embree {
    fn lib_name(&self) -> String {
        format!("embree{}", self.major)
    }
}

const MAJORS: [u32; 2] = [4, 3];

const HOW_TO_INSTALL: &str = "\
embree-sys: cannot find Intel Embree 4 or 3 (looked at $EMBREE_DIR, pkg-config \
embree4/embree3, /usr/include, /usr/local/include and the usual library directories). \
Install it (Debian/Ubuntu: `apt-get install libembree-dev`; Fedora: `dnf install embree-devel`; \
macOS: `brew install embree`) or set EMBREE_DIR to a prefix holding \
include/embree4/rtcore.h (or include/embree3/rtcore.h) and lib/libembree4.so (or libembree3.so)";

/// Stops the build with `message` shown as a Cargo error (no panic, no backtrace).
fn fail(message: &str) -> ! {
    for line in message.lines() {
        println!("cargo::error={line}");
    }
    // `cargo::error` fails the build once the script has ended; exit cleanly.
    std::process::exit(0)
}

fn main() {
    println!("cargo::rerun-if-env-changed=DOCS_RS");
    println!("cargo::rerun-if-env-changed=EMBREE_DIR");
    println!("cargo::rerun-if-env-changed=PKG_CONFIG_PATH");
    println!("cargo::rerun-if-changed=shim/shim.c");
    println!("cargo::rerun-if-changed=shim/shim.h");
    println!("cargo::rustc-check-cfg=cfg(embree3)");
    println!("cargo::rustc-check-cfg=cfg(embree4)");

    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    if env::var_os("DOCS_RS").is_some() {
        // docs.rs has no Embree: document the pre-generated Embree 3 bindings,
        // compile no shim and link nothing (rustdoc does not link).
        println!("cargo::rustc-cfg=embree3");
        if let Err(e) = std::fs::copy("src/docs_rs_bindings.rs", out.join("bindings.rs")) {
            fail(&format!(
                "embree-sys: cannot copy the docs.rs bindings to OUT_DIR: {e}"
            ));
        }
        return;
    }

    let embree = match find_embree() {
        Ok(Some(embree)) => embree,
        Ok(None) => fail(HOW_TO_INSTALL),
        Err(message) => fail(&message),
    };
    let header = embree
        .include_dir
        .join(format!("embree{}", embree.major))
        .join("rtcore.h");
    println!("cargo::rerun-if-changed={}", header.display());
    // Visible with `cargo build -vv`; a warning on every rebuild would be noise.
    eprintln!(
        "embree-sys: using Embree {} from {} ({})",
        embree.major,
        embree.include_dir.display(),
        embree.source
    );

    let major_define = embree.major.to_string();
    cc::Build::new()
        .file("shim/shim.c")
        .include(&embree.include_dir)
        .define("APM_EMBREE_MAJOR", major_define.as_str())
        .warnings(true)
        .try_compile("apm_embree_shim")
        .unwrap_or_else(|e| fail(&format!("embree-sys: cannot compile shim/shim.c: {e}")));

    if let Some(dir) = &embree.lib_dir {
        println!("cargo::rustc-link-search=native={}", dir.display());
    }
    println!("cargo::rustc-link-lib=dylib={}", embree.lib_name());
    println!("cargo::rustc-cfg=embree{}", embree.major);
    println!("cargo::metadata=version_major={}", embree.major);
    println!("cargo::metadata=include={}", embree.include_dir.display());

    let bindings = bindgen::Builder::default()
        .header("shim/shim.h")
        .clang_arg(format!("-I{}", embree.include_dir.display()))
        .clang_arg(format!("-DAPM_EMBREE_MAJOR={}", embree.major))
        .allowlist_function("rtc.*")
        .allowlist_function("apm_.*")
        .allowlist_type("RTC.*")
        .allowlist_var("RTC.*")
        // C enums become plain integer constants with their C names
        // (`RTC_ERROR_NONE: RTCError`), the same spelling in both majors.
        .default_enum_style(bindgen::EnumVariation::Consts)
        .prepend_enum_name(false)
        .derive_default(true)
        .derive_debug(true)
        .layout_tests(true)
        .parse_callbacks(Box::new(bindgen::CargoCallbacks::new()))
        .generate();
    let bindings = match bindings {
        Ok(b) => b,
        Err(e) => fail(&format!(
            "embree-sys: bindgen could not parse {} ({e}); is libclang installed \
             (`apt-get install libclang-dev`)?",
            header.display()
        )),
    };
    if let Err(e) = bindings.write_to_file(out.join("bindings.rs")) {
        fail(&format!(
            "embree-sys: cannot write bindings.rs to OUT_DIR: {e}"
        ));
    }
}

/// The Embree to build against; `Ok(None)` when none was found, `Err` when
/// `EMBREE_DIR` names a folder without one.
fn find_embree() -> Result<Option<Embree>, String> {
    if let Some(dir) = env::var_os("EMBREE_DIR") {
        let dir = PathBuf::from(dir);
        return match from_prefix(&dir) {
            Some(embree) => Ok(Some(embree)),
            None => Err(format!(
                "embree-sys: EMBREE_DIR={} holds neither include/embree4/rtcore.h nor \
                 include/embree3/rtcore.h; point it at an Embree install prefix or unset it \
                 to search the system (`apt-get install libembree-dev`)",
                dir.display()
            )),
        };
    }
    Ok(from_pkg_config().or_else(from_standard_dirs))
}

fn has_header(include_dir: &Path, major: u32) -> bool {
    include_dir
        .join(format!("embree{major}"))
        .join("rtcore.h")
        .is_file()
}

fn has_library(dir: &Path, major: u32) -> bool {
    let stem = format!("libembree{major}");
    [
        format!("{stem}.so"),
        format!("{stem}.so.{major}"),
        format!("{stem}.dylib"),
        format!("{stem}.a"),
        format!("embree{major}.lib"),
    ]
    .iter()
    .any(|name| dir.join(name).exists())
}

fn from_prefix(prefix: &Path) -> Option<Embree> {
    let include_dir = prefix.join("include");
    let major = MAJORS.into_iter().find(|&m| has_header(&include_dir, m))?;
    let lib_dir = ["lib", "lib64"]
        .iter()
        .map(|l| prefix.join(l))
        .find(|d| has_library(d, major))
        .unwrap_or_else(|| prefix.join("lib"));
    Some(Embree {
        major,
        include_dir,
        lib_dir: Some(lib_dir),
        source: "EMBREE_DIR".into(),
    })
}

/// Asks `pkg-config` (if installed) for `embree4`, then `embree3`.
fn from_pkg_config() -> Option<Embree> {
    for major in MAJORS {
        let name = format!("embree{major}");
        let Ok(out) = Command::new("pkg-config")
            .args(["--cflags-only-I", "--libs-only-L", &name])
            .output()
        else {
            return None; // no pkg-config binary at all
        };
        if !out.status.success() {
            continue;
        }
        let flags = String::from_utf8_lossy(&out.stdout).into_owned();
        let mut includes: Vec<PathBuf> = flags
            .split_whitespace()
            .filter_map(|f| f.strip_prefix("-I"))
            .map(PathBuf::from)
            .collect();
        // pkg-config hides system include dirs; fall back to them.
        includes.extend(["/usr/include", "/usr/local/include"].map(PathBuf::from));
        let lib_dir = flags
            .split_whitespace()
            .filter_map(|f| f.strip_prefix("-L"))
            .map(PathBuf::from)
            .next();
        if let Some(include_dir) = includes.into_iter().find(|d| has_header(d, major)) {
            return Some(Embree {
                major,
                include_dir,
                lib_dir,
                source: format!("pkg-config {name}"),
            });
        }
    }
    None
}

fn from_standard_dirs() -> Option<Embree> {
    let arch = env::var("CARGO_CFG_TARGET_ARCH").unwrap_or_else(|_| "x86_64".into());
    let include_dirs = [
        "/usr/include",
        "/usr/local/include",
        "/opt/homebrew/include",
    ];
    let lib_dirs = [
        format!("/usr/lib/{arch}-linux-gnu"),
        "/usr/lib64".into(),
        "/usr/lib".into(),
        "/usr/local/lib".into(),
        "/usr/local/lib64".into(),
        "/opt/homebrew/lib".into(),
    ];
    for major in MAJORS {
        for inc in include_dirs {
            let inc = Path::new(inc);
            if !has_header(inc, major) {
                continue;
            }
            match lib_dirs
                .iter()
                .map(PathBuf::from)
                .find(|d| has_library(d, major))
            {
                Some(lib_dir) => {
                    return Some(Embree {
                        major,
                        include_dir: inc.to_path_buf(),
                        lib_dir: Some(lib_dir),
                        source: "standard directories".into(),
                    })
                }
                None => println!(
                    "cargo::warning=embree-sys: found {}/embree{major}/rtcore.h but no \
                     libembree{major} library; trying the next candidate",
                    inc.display()
                ),
            }
        }
    }
    None
}
