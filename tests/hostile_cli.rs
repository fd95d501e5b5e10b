//! Hostile command lines and output targets (issue 12): the CLI answers with a
//! clear error and exit code 1 or 2, never an abort, a panic (101), an
//! out-of-memory kill, or a destroyed device file.

use std::os::unix::fs::FileTypeExt;
use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn hostile(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/hostile")
        .join(name)
}

/// Runs the CLI under a 2 GiB address-space limit.
fn run_limited(args: &[&str]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_adaptive-pm"));
    cmd.args(args);
    // SAFETY: setrlimit is async-signal-safe and only touches the child.
    unsafe {
        cmd.pre_exec(|| {
            let lim = libc::rlimit {
                rlim_cur: 2 << 30,
                rlim_max: 2 << 30,
            };
            if libc::setrlimit(libc::RLIMIT_AS, &lim) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    cmd.output().expect("the CLI runs")
}

/// Asserts a clean failure whose stderr holds `words`.
fn refused(out: &Output, words: &[&str]) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.signal().is_none(), "killed by a signal: {err}");
    let code = out.status.code().unwrap();
    assert!(code == 1 || code == 2, "exit code {code}: {err}");
    assert!(!err.contains("panicked"), "{err}");
    for w in words {
        assert!(err.contains(w), "`{err}` lacks `{w}`");
    }
}

#[test]
fn memory_classes_fail_cleanly_under_a_2_gib_limit() {
    for (file, word) in [
        ("sparse_count_2p31.gltf", "without a bufferView"),
        ("accessor_count_huge.gltf", "elements need"),
        ("node_dag_40_levels.gltf", "node instances"),
        ("buffer_uri_dev_zero.gltf", "/dev/zero"),
        ("buffer_byte_length_2p40.gltf", "buffers declare"),
    ] {
        let out = run_limited(&["scene", hostile(file).to_str().unwrap()]);
        refused(&out, &[word]);
    }
}

#[test]
fn hostile_numbers_are_refused() {
    let base = hostile("base.gltf");
    let base = base.to_str().unwrap();
    let out = run_limited(&["trace", base, "--threads", "100000"]);
    refused(&out, &["threads", "per available core"]);
    let out = run_limited(&["trace", base, "--n-max", "18446744073709551615"]);
    refused(&out, &["photon budget exceeded"]);
    let out = run_limited(&["trace", base, "--budget-mb", "18446744073709551615"]);
    refused(&out, &["--budget-mb"]);
    let out = run_limited(&["trace", base, "--cosn", "nan"]);
    refused(&out, &["not a finite number"]);
    let tmp = tempfile::tempdir().unwrap();
    let exr = tmp.path().join("a.exr");
    let out = run_limited(&[
        "render",
        base,
        "--out",
        exr.to_str().unwrap(),
        "--exposure",
        "nan",
    ]);
    refused(&out, &["not a finite number"]);
    assert!(!exr.exists());
}

#[test]
fn output_targets_that_are_not_regular_files_are_refused() {
    let base = hostile("base.gltf");
    let tmp = tempfile::tempdir().unwrap();
    let fifo = tmp.path().join("fifo.exr");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: mkfifo reads a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let link = tmp.path().join("link.exr");
    std::os::unix::fs::symlink("/dev/null", &link).unwrap();
    for target in [Path::new("/dev/null"), &fifo, &link, tmp.path()] {
        let out = run_limited(&[
            "render",
            base.to_str().unwrap(),
            "--direct-only",
            "--width",
            "8",
            "--height",
            "8",
            "--out",
            target.to_str().unwrap(),
        ]);
        refused(&out, &[]);
    }
    assert!(std::fs::metadata("/dev/null")
        .unwrap()
        .file_type()
        .is_char_device());
    assert!(std::fs::symlink_metadata(&fifo)
        .unwrap()
        .file_type()
        .is_fifo());
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    // No temporary file is left behind.
    let left: Vec<_> = std::fs::read_dir(tmp.path()).unwrap().collect();
    assert_eq!(left.len(), 2);
}

#[test]
fn safe_writes_replace_whole_files_and_refuse_devices() {
    use adaptive_pm::output::{write_bytes, write_with};
    let tmp = tempfile::tempdir().unwrap();
    let p = tmp.path().join("out.csv");
    write_bytes(&p, b"first").unwrap();
    write_bytes(&p, b"second").unwrap();
    assert_eq!(std::fs::read(&p).unwrap(), b"second");
    // A failing writer leaves the old file whole and no temporary behind.
    let failed = write_with(&p, |w| {
        w.write_all(b"half")?;
        Err(std::io::Error::other("killed"))
    });
    assert!(failed.is_err());
    assert_eq!(std::fs::read(&p).unwrap(), b"second");
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 1);
    assert!(write_bytes("/dev/null", b"x").is_err());
    assert!(write_bytes(tmp.path(), b"x").is_err());
    assert!(write_bytes(tmp.path().join("missing/out.csv"), b"x").is_err());
    assert!(std::fs::metadata("/dev/null")
        .unwrap()
        .file_type()
        .is_char_device());
}

#[test]
fn encoders_that_open_a_path_write_in_a_private_folder() {
    use adaptive_pm::output::write_via_path;
    use std::os::unix::fs::PermissionsExt;
    let tmp = tempfile::tempdir().unwrap();
    let p = tmp.path().join("fig.png");
    write_via_path(&p, |inner| {
        // The encoder sees the target's name (its extension picks the
        // format) inside a folder only we can enter.
        assert_eq!(inner.file_name(), p.file_name());
        let mode = std::fs::metadata(inner.parent().unwrap())
            .unwrap()
            .permissions()
            .mode();
        assert_eq!(mode & 0o077, 0, "mode {mode:o}");
        std::fs::write(inner, b"png")
    })
    .unwrap();
    assert_eq!(std::fs::read(&p).unwrap(), b"png");
    // A failing encoder leaves the target whole and nothing beside it.
    let failed = write_via_path(&p, |inner| {
        std::fs::write(inner, b"half")?;
        Err(std::io::Error::other("killed"))
    });
    assert!(failed.is_err());
    assert_eq!(std::fs::read(&p).unwrap(), b"png");
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 1);
}
