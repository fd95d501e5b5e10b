//! How many photons a caustic pass emits ([`super::caustic`]): the
//! default, a share of `N_MAX` that follows the quality knob, or a count.

use super::caustic_aim::CausticAim;
use crate::error::{Error, Result};
use crate::scene::Scene;

/// The default caustic photon count as a share of `N_MAX`
/// ([`default_caustic_photons`]).
pub const DEFAULT_CAUSTIC_SHARE: f64 = 1.0;

/// The caustic photons a run emits by default: `DEFAULT_CAUSTIC_SHARE *
/// N_MAX` when the scene has a specular mesh and a light, else 0. It
/// follows the quality knob as `N_MAX` does (`Q^2 INT_MAX`).
pub fn default_caustic_photons(scene: &Scene, n_max: u64) -> u64 {
    if scene.lights().is_empty() || CausticAim::new(scene).is_empty() {
        0
    } else {
        (n_max as f64 * DEFAULT_CAUSTIC_SHARE).round() as u64
    }
}

/// How many photons a caustic pass emits: the default for the scene and
/// `N_MAX` ([`default_caustic_photons`]), or a count (0: no pass).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub enum CausticBudget {
    /// [`default_caustic_photons`].
    #[default]
    Auto,
    /// This many (0: no pass).
    Photons(u64),
}

impl CausticBudget {
    /// The count for a scene and `N_MAX`.
    pub fn photons(self, scene: &Scene, n_max: u64) -> u64 {
        match self {
            CausticBudget::Auto => default_caustic_photons(scene, n_max),
            CausticBudget::Photons(n) => n,
        }
    }
}

impl std::fmt::Display for CausticBudget {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CausticBudget::Auto => f.write_str("auto"),
            CausticBudget::Photons(n) => write!(f, "{n}"),
        }
    }
}

impl std::str::FromStr for CausticBudget {
    type Err = Error;
    /// `auto` or a photon count.
    fn from_str(s: &str) -> Result<Self> {
        match s.trim() {
            "auto" => Ok(CausticBudget::Auto),
            n => n.parse().map(CausticBudget::Photons).map_err(|_| {
                Error::param(
                    "caustic photons",
                    format!("`{s}` is neither `auto` nor a photon count"),
                )
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budgets_parse_and_refuse_by_name() {
        assert_eq!(
            "auto".parse::<CausticBudget>().unwrap(),
            CausticBudget::Auto
        );
        assert_eq!(
            " 1000 ".parse::<CausticBudget>().unwrap(),
            CausticBudget::Photons(1000)
        );
        for bad in ["", "-1", "1e6", "many"] {
            let e = bad.parse::<CausticBudget>().unwrap_err().to_string();
            assert!(e.contains("caustic photons"), "{bad}: {e}");
        }
        assert_eq!(CausticBudget::Photons(7).to_string(), "7");
    }
}
