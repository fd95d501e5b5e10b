//! Emission profiles of area lights. One file per profile.

pub mod cosn;

pub use cosn::CosN;
