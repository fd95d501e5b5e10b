//! `--n-sweep` parsing through the public API: ranges against their closed
//! form, lists, and malformed input rejected with the syntax in the message.

use adaptive_pm::experiments::sweep::{parse_sweep, MAX_SWEEP_POINTS};

#[test]
fn ranges_match_their_closed_form() {
    for (a, b, step) in [
        (0.0f64, 10.0, 1.0),
        (1.0, 200.0, 1.0),
        (0.5, 3.0, 0.25),
        (2.0, 9.0, 3.0),
    ] {
        let v = parse_sweep(&format!("{a}..{b}:{step}")).unwrap();
        let count = ((b - a) / step + 1e-9).floor() as usize + 1;
        assert_eq!(v.len(), count, "{a}..{b}:{step}");
        for (i, x) in v.iter().enumerate() {
            assert!(
                (x - (a + i as f64 * step)).abs() < 1e-9,
                "{a}..{b}:{step} [{i}] = {x}"
            );
            assert!((a..=b).contains(x));
        }
    }
    assert_eq!(parse_sweep("1..200").unwrap().len(), 200);
}

#[test]
fn lists_keep_their_order() {
    assert_eq!(parse_sweep("200,0,20").unwrap(), [200.0, 0.0, 20.0]);
    assert_eq!(parse_sweep("1e2,0.5").unwrap(), [100.0, 0.5]);
}

#[test]
fn malformed_sweeps_are_rejected_with_the_syntax() {
    for s in [
        "",
        "1-200",
        "1...5",
        "x..3",
        "3..1",
        "0..5:0",
        "-2",
        "NaN",
        "1..1e300:1e-300",
    ] {
        let e = parse_sweep(s).expect_err(s).to_string();
        assert!(e.contains("A..B:STEP") && e.contains("n sweep"), "{s}: {e}");
    }
    let big = format!("0..{}", MAX_SWEEP_POINTS);
    assert!(parse_sweep(&big).is_err(), "one more than the cap");
    assert!(parse_sweep(&format!("1..{}", MAX_SWEEP_POINTS)).is_ok());
}

#[test]
fn density_targets_parse() {
    use adaptive_pm::experiments::cornell::SweepDensityTarget;
    assert_eq!(
        "mean".parse::<SweepDensityTarget>().unwrap(),
        SweepDensityTarget::ReferenceMean
    );
    assert_eq!(
        "max".parse::<SweepDensityTarget>().unwrap(),
        SweepDensityTarget::ReferenceMax
    );
    assert_eq!(
        "0.25".parse::<SweepDensityTarget>().unwrap(),
        SweepDensityTarget::PerArea(0.25)
    );
    for bad in ["", "0", "-1", "NaN", "inf", "maximum"] {
        assert!(bad.parse::<SweepDensityTarget>().is_err(), "{bad}");
    }
}
