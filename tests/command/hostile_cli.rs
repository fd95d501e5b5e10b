//! Hostile command lines and output targets (issue 12): the CLI answers with a
//! clear error and exit code 1 or 2, never an abort, a panic (101), an
//! out-of-memory kill, or a destroyed device file.

use adaptive_pm::photon_file::{ByteHash, Header, MapHash, HEADER_SIZE, TRAILER_SIZE};
use std::io::Read;
use std::os::unix::fs::FileTypeExt;
use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use crate::common;

fn hostile(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/hostile")
        .join(name)
}

/// Runs the CLI under a 2 GiB address-space limit; a run that has not ended
/// after [`HANG_LIMIT`] is killed and the test fails (a FIFO opened for
/// reading blocks forever: the test must not).
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
    output_within(cmd, HANG_LIMIT)
}

/// Far above any run of these tests (each well under a second).
const HANG_LIMIT: Duration = Duration::from_secs(30);

/// `cmd.output()`, but the child is killed (and the test fails) after `limit`.
fn output_within(mut cmd: Command, limit: Duration) -> Output {
    cmd.stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let mut child = cmd.spawn().expect("the CLI runs");
    // Drained on threads: a child blocked on a full pipe would look hung.
    let drain = |pipe: Option<Box<dyn Read + Send>>| {
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            if let Some(mut p) = pipe {
                let _ = p.read_to_end(&mut bytes);
            }
            bytes
        })
    };
    let stdout = drain(child.stdout.take().map(|p| Box::new(p) as _));
    let stderr = drain(child.stderr.take().map(|p| Box::new(p) as _));
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{cmd:?} still running after {limit:?}: it hangs");
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    Output {
        status,
        stdout: stdout.join().unwrap(),
        stderr: stderr.join().unwrap(),
    }
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

/// A FIFO at `path`.
fn mkfifo(path: &Path) {
    let c = std::ffi::CString::new(path.to_str().unwrap()).unwrap();
    // SAFETY: mkfifo reads a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Asserts a successful run.
fn ok(out: &Output) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Traces shard `i` of 2 of the hostile base scene into `dir` (1000 photons).
fn shard_file(dir: &Path, i: u32) -> PathBuf {
    let path = dir.join(format!("s{i}.apm"));
    let base = hostile("base.gltf");
    let shard = format!("{i}/2");
    let args = ["trace", s(&base), "--n-max", "1000", "--shard", &shard];
    ok(&run_limited(&[&args[..], &["--out", s(&path)]].concat()));
    path
}

/// Both shards of the base scene's run, and their merged map.
fn shards_and_map(dir: &Path) -> (PathBuf, PathBuf, PathBuf) {
    let (s0, s1) = (shard_file(dir, 0), shard_file(dir, 1));
    let map = dir.join("map.apm");
    ok(&run_limited(&["merge", s(&s0), s(&s1), "--out", s(&map)]));
    (s0, s1, map)
}

/// Copies photon file `src` to `dst` with its header changed by `edit`, then
/// reseals it as a writer would: the header's map checksum and the trailer's
/// file checksum are recomputed, so only the edited field is wrong.
fn craft(src: &Path, dst: &Path, edit: impl FnOnce(&mut Header)) {
    let mut bytes = std::fs::read(src).unwrap();
    let mut h = Header::from_bytes(&bytes).unwrap();
    edit(&mut h);
    let announced = MapHash {
        count: h.photons,
        sum: h.photon_sum,
    };
    h.map_checksum = announced.checksum(&h.frame());
    bytes[..HEADER_SIZE].copy_from_slice(&h.to_bytes());
    let body = bytes.len() - TRAILER_SIZE as usize;
    let mut hash = ByteHash::default();
    hash.update(&bytes[..body]);
    bytes[body + 8..].copy_from_slice(&hash.value().to_le_bytes());
    std::fs::write(dst, bytes).unwrap();
}

#[test]
fn fifo_and_device_inputs_are_refused_without_blocking() {
    let tmp = tempfile::tempdir().unwrap();
    let base = hostile("base.gltf");
    let fifo = |name: &str| {
        let p = tmp.path().join(name);
        mkfifo(&p);
        p
    };
    let (gltf, apm, exr) = (fifo("in.gltf"), fifo("in.apm"), fifo("in.exr"));
    let out_apm = tmp.path().join("out.apm");
    let out_exr = tmp.path().join("out.exr");
    for args in [
        vec!["scene", s(&gltf)],
        vec!["trace", s(&gltf), "--n-max", "100"],
        vec!["merge", s(&apm), "--out", s(&out_apm)],
        vec!["assemble", s(&exr), "--out", s(&out_exr)],
        vec![
            "render",
            s(&base),
            "--map",
            s(&apm),
            "--width",
            "8",
            "--height",
            "8",
            "--out",
            s(&out_exr),
        ],
    ] {
        refused(&run_limited(&args), &["FIFO", "only regular files"]);
    }
    // Devices never end (/dev/zero read until the memory ran out).
    for dev in ["/dev/zero", "/dev/urandom"] {
        refused(&run_limited(&["scene", dev]), &[dev, "a device"]);
    }
    refused(
        &run_limited(&["merge", "/dev/zero", "--out", s(&out_apm)]),
        &["a device"],
    );
    assert!(!out_apm.exists() && !out_exr.exists());
}

#[test]
fn merge_refuses_a_huge_shard_count_without_allocating_from_it() {
    let tmp = tempfile::tempdir().unwrap();
    let s0 = shard_file(tmp.path(), 0);
    let huge = tmp.path().join("huge.apm");
    craft(&s0, &huge, |h| h.shard_count = u32::MAX);
    let out = tmp.path().join("out.apm");
    let run = run_limited(&["merge", s(&huge), "--out", s(&out)]);
    refused(&run, &["missing shard(s) 1, 2,", "more of 4294967295"]);
    // An index past the count is refused when the file is opened.
    let past = tmp.path().join("past.apm");
    craft(&s0, &past, |h| h.shard_index = 5);
    let run = run_limited(&["merge", s(&past), "--out", s(&out)]);
    refused(&run, &["past.apm", "shard 5/2"]);
    assert!(!out.exists());
}

#[test]
fn merge_refuses_counters_that_overflow_and_nan_frames() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let (s0, s1) = (shard_file(d, 0), shard_file(d, 1));
    let out = d.join("out.apm");
    // Each header is plausible alone; their sum wraps past u64::MAX.
    let big = |h: &mut Header| {
        h.emitted = 1 << 63;
        h.emitted_total = u64::MAX;
    };
    let (e0, e1) = (d.join("e0.apm"), d.join("e1.apm"));
    craft(&s0, &e0, big);
    craft(&s1, &e1, big);
    let run = run_limited(&["merge", s(&e0), s(&e1), "--out", s(&out)]);
    refused(&run, &["emitted counts overflow 64 bits"]);
    // A NaN frame is a bad header, not "shards of different runs".
    let (n0, n1) = (d.join("n0.apm"), d.join("n1.apm"));
    craft(&s0, &n0, |h| h.frame_min.x = f32::NAN);
    craft(&s1, &n1, |h| h.frame_min.x = f32::NAN);
    let run = run_limited(&["merge", s(&n0), s(&n1), "--out", s(&out)]);
    refused(&run, &["n0.apm", "frame bounds"]);
    assert!(!String::from_utf8_lossy(&run.stderr).contains("different"));
    // Shards whose emission does not add up to their run's total.
    let short = d.join("short.apm");
    craft(&s1, &short, |h| h.emitted -= 1);
    let run = run_limited(&["merge", s(&s0), s(&short), "--out", s(&out)]);
    refused(&run, &["photons together, but their run emits"]);
    assert!(!out.exists());
}

#[test]
fn render_map_refuses_an_unmerged_shard_and_bad_headers() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let (s0, _, map) = shards_and_map(d);
    let base = hostile("base.gltf");
    let img = d.join("v.exr");
    let render = |map: &Path| {
        let args = [
            "render",
            s(&base),
            "--map",
            s(map),
            "--width",
            "8",
            "--height",
            "8",
        ];
        run_limited(&[&args[..], &["--out", s(&img)]].concat())
    };
    ok(&render(&map));
    std::fs::remove_file(&img).unwrap();
    // Alone, shard 0 holds half the light: merge first.
    refused(&render(&s0), &["shard 0/2", "merge every shard first"]);
    type Edit = fn(&mut Header);
    let cases: [(&str, Edit, &str); 5] = [
        ("ps_max", |h| h.power_scale = 3.4e38, "power scale 3.4e38"),
        (
            "ps_inf",
            |h| h.power_scale = f32::INFINITY,
            "power scale inf",
        ),
        ("ps_nan", |h| h.power_scale = f32::NAN, "power scale NaN"),
        ("frame_nan", |h| h.frame_max.z = f32::NAN, "frame bounds"),
        (
            "merged_2",
            |h| h.shard_count = 2,
            "merged map must be shard 0/1",
        ),
    ];
    for (name, edit, expect) in cases {
        let bad = d.join(format!("{name}.apm"));
        craft(&map, &bad, edit);
        refused(&render(&bad), &[name, expect]);
    }
    // Edited without resealing: the header's map checksum gives it away.
    let mut bytes = std::fs::read(&map).unwrap();
    bytes[120..124].copy_from_slice(&1024f32.to_le_bytes()); // power_scale
    let unsealed = d.join("unsealed.apm");
    std::fs::write(&unsealed, bytes).unwrap();
    refused(&render(&unsealed), &["map checksum does not match"]);
    assert!(!img.exists());
}

/// The 16x16 image the base scene renders (direct light only: fast).
fn small_exr(dir: &Path) -> PathBuf {
    let p = dir.join("whole.exr");
    let base = hostile("base.gltf");
    let args = ["render", s(&base), "--direct-only", "--spp", "1"];
    let size = ["--width", "16", "--height", "16", "--out", s(&p)];
    ok(&run_limited(&[&args[..], &size[..]].concat()));
    p
}

#[test]
fn assemble_checks_tile_headers_before_allocating_pixels() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let whole = small_exr(d);
    let out = d.join("out.exr");
    // The untouched image assembles (one tile of all its rows).
    ok(&run_limited(&["assemble", s(&whole), "--out", s(&out)]));
    std::fs::remove_file(&out).unwrap();
    // A 1 KB file claiming 30000x30000 (10.8 GB of pixels), then 16000x16000
    // (within the size limit, but not in a file this small).
    for (side, expect) in [(30000, "must be in 1..=16384"), (16000, "blocks of pixels")] {
        let mut bytes = std::fs::read(&whole).unwrap();
        common::claim_exr_size(&mut bytes, side);
        let big = d.join(format!("big{side}.exr"));
        std::fs::write(&big, bytes).unwrap();
        let run = run_limited(&["assemble", s(&big), "--out", s(&out)]);
        refused(&run, &[&format!("big{side}.exr"), expect]);
    }
    // The output may not replace a tile.
    let spelled = d.join(".").join("whole.exr");
    let run = run_limited(&["assemble", s(&whole), "--out", s(&spelled)]);
    refused(&run, &["also the input"]);
    assert!(!out.exists());
}

#[test]
fn outputs_that_are_inputs_by_another_spelling_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let pf = d.join("pf");
    std::fs::create_dir(&pf).unwrap();
    let (s0, s1) = (shard_file(&pf, 0), shard_file(&pf, 1));
    let before = std::fs::read(&s0).unwrap();
    let link = d.join("link.apm");
    std::os::unix::fs::symlink(&s0, &link).unwrap();
    let hard = d.join("hard.apm");
    std::fs::hard_link(&s0, &hard).unwrap();
    for out in [
        pf.join("..").join("pf").join("s0.apm"),
        pf.join(".").join("s0.apm"),
        link,
        hard,
    ] {
        let run = run_limited(&["merge", s(&s0), s(&s1), "--out", s(&out)]);
        refused(&run, &["--out", "also the input", "s0.apm"]);
    }
    assert_eq!(std::fs::read(&s0).unwrap(), before);
    // trace x.gltf --out x.gltf replaced the scene with photons.
    let scene = d.join("victim.gltf");
    std::fs::copy(hostile("base.gltf"), &scene).unwrap();
    let scene_before = std::fs::read(&scene).unwrap();
    let spelled = pf.join("..").join("victim.gltf");
    let run = run_limited(&["trace", s(&scene), "--n-max", "100", "--out", s(&spelled)]);
    refused(&run, &["also the input", "victim.gltf"]);
    assert_eq!(std::fs::read(&scene).unwrap(), scene_before);
    // render: its EXR over the scene or the map, its PNG over its EXR.
    let small = [
        "--width", "8", "--height", "8", "--spp", "1", "--n-max", "100",
    ];
    let run = run_limited(&[&["render", s(&scene)][..], &small, &["--out", s(&spelled)]].concat());
    refused(&run, &["also the input", "victim.gltf"]);
    assert_eq!(std::fs::read(&scene).unwrap(), scene_before);
    let map = d.join("map.apm");
    let run = run_limited(&["merge", s(&s0), s(&s1), "--out", s(&map)]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let map_before = std::fs::read(&map).unwrap();
    let spelled_map = pf.join("..").join("map.apm");
    let run = run_limited(
        &[
            &["render", s(&scene), "--map", s(&map)][..],
            &small,
            &["--out", s(&spelled_map)],
        ]
        .concat(),
    );
    refused(&run, &["also the input", "map.apm"]);
    assert_eq!(std::fs::read(&map).unwrap(), map_before);
    let exr = d.join("same.exr");
    let run = run_limited(
        &[
            &["render", s(&scene)][..],
            &small,
            &[
                "--out",
                s(&exr),
                "--png",
                s(&pf.join("..").join("same.exr")),
            ],
        ]
        .concat(),
    );
    refused(&run, &["also the input", "same.exr"]);
}

#[test]
fn trace_checks_its_output_before_tracing() {
    let tmp = tempfile::tempdir().unwrap();
    let base = hostile("base.gltf");
    let missing = tmp.path().join("missing").join("x.apm");
    // A run this large would take minutes: the refusal comes first.
    let args = ["trace", s(&base), "--n-max", "2000000000", "--json"];
    let run = run_limited(&[&args[..], &["--out", s(&missing)]].concat());
    refused(&run, &["--out", "output folder does not exist", "x.apm"]);
    assert!(run.stdout.is_empty(), "it traced");
    // A folder or a device as the photon file, likewise.
    for out in [tmp.path(), Path::new("/dev/null")] {
        let run = run_limited(&[&args[..], &["--out", s(out)]].concat());
        refused(&run, &["--out"]);
        assert!(run.stdout.is_empty(), "it traced");
    }
}
