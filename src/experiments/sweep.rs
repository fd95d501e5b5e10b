//! The `--n-sweep` syntax: which light exponents `n` an experiment visits.
//!
//! - `A..B`: every value from `A` to `B` inclusive, step 1 (`1..200` is 200 values);
//! - `A..B:STEP`: the same with a step (`0..200:50` is 0, 50, 100, 150, 200);
//! - `a,b,c`: a list; each item may itself be a range (`0,10..12`).
//!
//! Values are reals, finite and >= 0 (an exponent of `cos^n`). A range's end is
//! included when it lies on the grid to within a millionth of a step, so
//! `0..1:0.1` ends at 1 despite rounding. A sweep holds at most
//! [`MAX_SWEEP_POINTS`] values, so a typo like `0..1e9` is an error rather than a
//! run that never ends.

use crate::error::{Error, Result};

/// Largest number of values a sweep may hold.
pub const MAX_SWEEP_POINTS: usize = 100_000;

/// The syntax, repeated in every error message.
pub const SWEEP_SYNTAX: &str = "expected A..B (inclusive, step 1), A..B:STEP, or a comma list \
     such as 0,20,200; values finite and >= 0";

fn bad(reason: String) -> Error {
    Error::param("n sweep", format!("{reason}; {SWEEP_SYNTAX}"))
}

fn number(s: &str) -> Result<f64> {
    let t = s.trim();
    let v: f64 = t
        .parse()
        .map_err(|_| bad(format!("`{t}` is not a number")))?;
    if !v.is_finite() || v < 0.0 {
        return Err(bad(format!("`{t}` is not a finite value >= 0")));
    }
    Ok(v)
}

fn push_range(item: &str, lo: &str, rest: &str, out: &mut Vec<f64>) -> Result<()> {
    let (hi, step) = match rest.split_once(':') {
        Some((hi, step)) => (number(hi)?, number(step)?),
        None => (number(rest)?, 1.0),
    };
    let lo = number(lo)?;
    if hi < lo {
        return Err(bad(format!("`{item}`: the end is below the start")));
    }
    if step <= 0.0 {
        return Err(bad(format!("`{item}`: the step must be > 0")));
    }
    let steps = ((hi - lo) / step + 1e-6).floor();
    if steps + 1.0 + out.len() as f64 > MAX_SWEEP_POINTS as f64 {
        return Err(bad(format!(
            "`{item}` has more than {MAX_SWEEP_POINTS} values"
        )));
    }
    for i in 0..=steps as usize {
        // the last grid point snaps to the end to undo accumulated rounding
        let v = lo + i as f64 * step;
        out.push(if (v - hi).abs() <= 1e-6 * step { hi } else { v });
    }
    Ok(())
}

/// Parses a sweep (see the module docs) into its values, in the order given.
///
/// # Errors
/// [`Error::InvalidParameter`] naming the bad item and showing the syntax: an
/// empty sweep or item, a value that is not a finite number >= 0, a range whose
/// end is below its start, a step <= 0, more than [`MAX_SWEEP_POINTS`] values.
pub fn parse_sweep(s: &str) -> Result<Vec<f64>> {
    let mut out = Vec::new();
    if s.trim().is_empty() {
        return Err(bad("the sweep is empty".into()));
    }
    for item in s.split(',') {
        let item = item.trim();
        if item.is_empty() {
            return Err(bad(format!("`{s}` has an empty item")));
        }
        match item.split_once("..") {
            Some((lo, rest)) => push_range(item, lo, rest, &mut out)?,
            None => {
                if out.len() >= MAX_SWEEP_POINTS {
                    return Err(bad(format!("more than {MAX_SWEEP_POINTS} values")));
                }
                out.push(number(item)?)
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_are_inclusive() {
        let v = parse_sweep("1..200").unwrap();
        assert_eq!(v.len(), 200);
        assert_eq!((v[0], v[199]), (1.0, 200.0));
        assert_eq!(
            parse_sweep("0..200:50").unwrap(),
            vec![0.0, 50.0, 100.0, 150.0, 200.0]
        );
        assert_eq!(parse_sweep("3..3").unwrap(), vec![3.0]);
        // 0.1 is not exact in binary: the end must still be reached, exactly
        let v = parse_sweep("0..1:0.1").unwrap();
        assert_eq!(v.len(), 11);
        assert_eq!(v[10], 1.0);
        // a step that does not divide the range stops before the end
        assert_eq!(parse_sweep("0..10:4").unwrap(), vec![0.0, 4.0, 8.0]);
    }

    #[test]
    fn lists_mix_values_and_ranges() {
        assert_eq!(parse_sweep(" 0, 20 ,200").unwrap(), vec![0.0, 20.0, 200.0]);
        assert_eq!(
            parse_sweep("0.5,10..12").unwrap(),
            vec![0.5, 10.0, 11.0, 12.0]
        );
        assert_eq!(parse_sweep("7").unwrap(), vec![7.0]);
    }

    #[test]
    fn bad_sweeps_are_errors_that_show_the_syntax() {
        for s in [
            "",
            " ",
            "a",
            "1..",
            "..5",
            "5..1",
            "1..5:0",
            "1..5:-1",
            "-1",
            "-1..3",
            "nan",
            "inf",
            "1..inf",
            "0,,2",
            "1,",
            "1..2..3",
            "1..5:x",
            "0..1e9",
            "0..1:1e-9",
        ] {
            let e = parse_sweep(s).expect_err(s).to_string();
            assert!(e.contains("A..B"), "{s}: {e}");
        }
    }
}
