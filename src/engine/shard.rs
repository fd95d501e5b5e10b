//! Which emitted photons a run traces: shard `index` of `count`
//! (docs/method.md, "Shards").
//!
//! Photon `i` of light `l` is keyed by `(seed, l, i)` and its whole path (every
//! child and bounce) by that key, so a shard that emits a subset of the ids
//! traces exactly those photons' paths, bit for bit as the whole run does.
//! Shard `I` of `N` takes, from each light's `n` photons, the contiguous ids
//! `[floor(n I / N), floor(n (I+1) / N))`: the shards partition every light's
//! ids, and each shard gets an even share of every light.

use crate::error::{Error, Result};
use std::ops::Range;

/// Shard `index` of `count` (0-based); `Shard::WHOLE` is the whole run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Shard {
    /// Which shard, in `0..count`.
    pub index: u32,
    /// How many shards the run is split into (>= 1).
    pub count: u32,
}

impl Default for Shard {
    fn default() -> Self {
        Shard::WHOLE
    }
}

impl Shard {
    /// The whole run: shard 0 of 1.
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    /// Shard `index` of `count`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] unless `count >= 1` and `index < count`.
    pub fn new(index: u32, count: u32) -> Result<Self> {
        let s = Shard { index, count };
        s.validate()?;
        Ok(s)
    }

    /// Checks `count >= 1` and `index < count`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the bad value.
    pub fn validate(&self) -> Result<()> {
        if self.count == 0 {
            return Err(Error::param("shard", "the shard count must be at least 1"));
        }
        if self.index >= self.count {
            return Err(Error::param(
                "shard",
                format!(
                    "index {} is not below the count {} (indices start at 0)",
                    self.index, self.count
                ),
            ));
        }
        Ok(())
    }

    /// True for the whole run.
    pub fn is_whole(&self) -> bool {
        self.count == 1
    }

    /// The ids this shard emits out of a light's `n` photons.
    pub fn range(&self, n: u64) -> Range<u64> {
        let at = |i: u32| (n as u128 * i as u128 / self.count as u128) as u64;
        at(self.index)..at(self.index + 1)
    }

    /// How many of a light's `n` photons this shard emits.
    pub fn len_of(&self, n: u64) -> u64 {
        let r = self.range(n);
        r.end - r.start
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl std::str::FromStr for Shard {
    type Err = Error;
    /// `I/N`, for example `0/4`.
    fn from_str(s: &str) -> Result<Self> {
        let bad = || Error::param("shard", format!("`{s}` is not I/N (for example 0/4)"));
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let i: u32 = i.trim().parse().map_err(|_| bad())?;
        let n: u32 = n.trim().parse().map_err(|_| bad())?;
        Shard::new(i, n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_partition_every_count() {
        for n in [0u64, 1, 2, 7, 100, 100_003] {
            for count in [1u32, 2, 3, 7, 64] {
                let mut next = 0;
                for index in 0..count {
                    let r = Shard { index, count }.range(n);
                    assert_eq!(r.start, next);
                    next = r.end;
                }
                assert_eq!(next, n);
            }
        }
    }

    #[test]
    fn parses_and_refuses() {
        assert_eq!(
            "2/7".parse::<Shard>().unwrap(),
            Shard { index: 2, count: 7 }
        );
        for bad in ["7/7", "0/0", "1", "a/2", "-1/2", ""] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
    }
}
