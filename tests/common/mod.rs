//! Helpers shared by the test binaries (each binary compiles its own copy
//! and uses part of it).
#![allow(dead_code)]

/// An error's message followed by its sources', `: `-separated.
pub fn chain(e: &dyn std::error::Error) -> String {
    let mut msg = e.to_string();
    let mut src = e.source();
    while let Some(s) = src {
        msg += &format!(": {s}");
        src = s.source();
    }
    msg
}

/// Overwrites the four i32 of the box2i attribute `name` in EXR `bytes`.
pub fn set_exr_box(bytes: &mut [u8], name: &str, b: [i32; 4]) {
    let key = format!("{name}\0box2i\0");
    let at = bytes
        .windows(key.len())
        .position(|w| w == key.as_bytes())
        .unwrap()
        + key.len()
        + 4;
    for (i, v) in b.iter().enumerate() {
        bytes[at + 4 * i..at + 4 * i + 4].copy_from_slice(&v.to_le_bytes());
    }
}

/// Makes a 1 KB EXR file (a copy of `bytes`) claim `side` x `side` pixels
/// in 64 x 64 blocks, the count its decoder checks against the size.
pub fn claim_exr_size(bytes: &mut [u8], side: i32) {
    let b = [0, 0, side - 1, side - 1];
    set_exr_box(bytes, "displayWindow", b);
    set_exr_box(bytes, "dataWindow", b);
    let blocks = ((side + 63) / 64).pow(2);
    let key = b"chunkCount\0int\0";
    let at = bytes.windows(key.len()).position(|w| w == key).unwrap() + key.len() + 4;
    bytes[at..at + 4].copy_from_slice(&blocks.to_le_bytes());
}

/// The variable `scripts/seed-sweep.sh` sets: each seeded statistical test
/// mixes it into its own seed ([`seed`]), so one sweep draws fresh photons
/// and samples for every test.
pub const SEED_ENV: &str = "ADAPTIVE_PM_TEST_SEED";

/// The seed a statistical test uses: `base` when [`SEED_ENV`] is unset (the
/// suite's fixed seeds), else a mix of `base` and the sweep's seed.
///
/// # Panics
/// When the variable is set but is not an unsigned integer.
pub fn seed(base: u64) -> u64 {
    match std::env::var(SEED_ENV) {
        Err(_) => base,
        Ok(v) => {
            let sweep: u64 = v
                .trim()
                .parse()
                .unwrap_or_else(|_| panic!("{SEED_ENV}={v:?} is not an unsigned integer"));
            // splitmix64 of the pair: distinct tests and sweeps never share a seed.
            let mut z = base ^ sweep.wrapping_mul(0x9e37_79b9_7f4a_7c15);
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        }
    }
}

/// The least number of its own measured sigmas a statistical bound spans.
pub const MIN_SIGMAS: f64 = 4.0;

/// Asserts that `deviation`, the difference between an estimate and what
/// it should be, lies within `bound`, and that `bound` is at least
/// [`MIN_SIGMAS`] times `sigma`, the noise of the estimate that the test
/// measured itself (a standard error from its own samples, independent
/// halves or repeated runs). Prints one `seed-sweep:` line first, which
/// `scripts/seed-sweep.sh` collects: the test, the check, the deviation in
/// sigmas and the bound in sigmas.
///
/// # Panics
/// When the deviation is outside the bound, when the bound is narrower than
/// [`MIN_SIGMAS`] sigmas, or when sigma is not finite and positive.
pub fn assert_within_noise(check: &str, deviation: f64, sigma: f64, bound: f64) {
    let test = std::thread::current()
        .name()
        .unwrap_or("unnamed")
        .to_string();
    let z = deviation.abs() / sigma;
    let bound_sigmas = bound / sigma;
    let ok = sigma.is_finite() && sigma > 0.0 && bound_sigmas >= MIN_SIGMAS && z <= bound_sigmas;
    let line = format!(
        "seed-sweep: test={test} check={} z={z:.3} bound_sigmas={bound_sigmas:.3} ok={ok}\n",
        check.replace(' ', "_")
    );
    eprint!("{line}");
    record_sweep_line(&line);
    assert!(
        sigma.is_finite() && sigma > 0.0,
        "{check}: the measured noise sigma = {sigma} is not finite and positive"
    );
    assert!(
        bound_sigmas >= MIN_SIGMAS,
        "{check}: the bound {bound:.4e} is only {bound_sigmas:.2} sigma of the measured noise \
         (sigma = {sigma:.4e}); a statistical bound spans at least {MIN_SIGMAS} sigma"
    );
    assert!(
        z <= bound_sigmas,
        "{check}: deviation {deviation:+.4e} is {z:.2} sigma (sigma = {sigma:.4e} measured \
         here), outside the bound {bound:.4e} = {bound_sigmas:.2} sigma"
    );
}

/// Where the seed sweep collects its lines: libtest's progress dots and the
/// output of tests running at the same time interleave with stderr mid-line,
/// so `scripts/seed-sweep.sh` names a file of its own for them.
pub const SWEEP_LOG_ENV: &str = "ADAPTIVE_PM_SWEEP_LOG";

/// Appends one whole line to the sweep's file, if one is named: a single
/// `write` on a file opened for appending, so lines of parallel tests never
/// mix.
fn record_sweep_line(line: &str) {
    use std::io::Write;
    let Some(path) = std::env::var_os(SWEEP_LOG_ENV) else {
        return;
    };
    let file = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&path);
    if let Err(e) = file.and_then(|mut f| f.write_all(line.as_bytes())) {
        panic!("{SWEEP_LOG_ENV}={}: {e}", path.to_string_lossy());
    }
}

/// [`assert_within_noise`] with the bound at exactly `k` sigmas (`k` at least
/// [`MIN_SIGMAS`]): for an estimate whose expected value is known exactly.
pub fn assert_sigmas(check: &str, deviation: f64, sigma: f64, k: f64) {
    assert_within_noise(check, deviation, sigma, k * sigma);
}

/// Mean and standard error of independent samples.
#[derive(Clone, Copy, Debug, Default)]
pub struct MeanVar {
    n: u64,
    mean: f64,
    m2: f64,
}

impl MeanVar {
    /// Adds one sample (Welford's update).
    pub fn push(&mut self, x: f64) {
        self.n += 1;
        let d = x - self.mean;
        self.mean += d / self.n as f64;
        self.m2 += d * (x - self.mean);
    }

    /// The samples of an iterator.
    pub fn of(xs: impl IntoIterator<Item = f64>) -> Self {
        let mut m = MeanVar::default();
        xs.into_iter().for_each(|x| m.push(x));
        m
    }

    /// Number of samples.
    pub fn count(&self) -> u64 {
        self.n
    }

    /// The sample mean.
    pub fn mean(&self) -> f64 {
        self.mean
    }

    /// The unbiased sample variance.
    pub fn variance(&self) -> f64 {
        if self.n < 2 {
            f64::NAN
        } else {
            self.m2 / (self.n - 1) as f64
        }
    }

    /// The standard error of the mean.
    pub fn std_error(&self) -> f64 {
        (self.variance() / self.n as f64).sqrt()
    }
}

/// The one-sided tail `P(T > t)` of Student's t with `dof` degrees of
/// freedom: `I_x(dof / 2, 1 / 2) / 2` with `x = dof / (dof + t^2)`, the
/// incomplete beta integrated by Simpson's rule after `s = 1 - u^2`, which
/// takes out its singularity at 1.
pub fn student_t_tail(t: f64, dof: u64) -> f64 {
    let a = dof as f64 / 2.0;
    let simpson = |lo: f64, hi: f64| {
        let n = 2000;
        let h = (hi - lo) / n as f64;
        let f = |u: f64| (1.0 - u * u).max(0.0).powf(a - 1.0);
        let inner: f64 = (1..n)
            .map(|i| f(lo + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 })
            .sum();
        (f(lo) + inner + f(hi)) * h / 3.0
    };
    let x = dof as f64 / (dof as f64 + t * t);
    0.5 * simpson((1.0 - x).sqrt(), 1.0) / simpson(0.0, 1.0)
}

/// The bound, in measured standard errors of a mean of `dof + 1` paired
/// samples, that `comparisons` one-sided tests exceed together with
/// probability `family_rate` (Bonferroni over Student's t; at least 4). A
/// test that takes the worst of many means estimated from few samples
/// would fail by chance against a plain 4-sigma bound.
pub fn family_bound(comparisons: usize, dof: u64, family_rate: f64) -> f64 {
    let target = family_rate / comparisons.max(1) as f64;
    let (mut lo, mut hi) = (4.0f64, 1e3f64);
    if student_t_tail(lo, dof) <= target {
        return lo;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if student_t_tail(mid, dof) > target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}
