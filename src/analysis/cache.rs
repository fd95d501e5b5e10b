//! Each distinct emission profile and BRDF is analysed once.
//!
//! The cache is keyed by the function's exact parameter bits
//! ([`crate::brdf::Brdf::param_bits`], the `cos^n` exponent's bits), not by
//! a hash of them, so two distinct functions never share an entry; the
//! estimator and the [`AnalysisParams`] are fixed at construction, so a key
//! always means the same answer.

use super::{analyze_brdf, analyze_emitter, AnalysisParams, DirectionalityTable, Estimator};
use crate::brdf::Brdf;
use crate::emitter::CosN;
use crate::error::Result;
use std::collections::HashMap;
use std::sync::Arc;

/// Memoised directionality of emitters and BRDFs.
#[derive(Clone, Debug)]
pub struct AnalysisCache {
    params: AnalysisParams,
    estimator: Estimator,
    /// By the exponent's bits (-0.0 folded into 0.0).
    emitters: HashMap<u32, f32>,
    brdfs: HashMap<(u8, [u32; crate::brdf::PARAM_WORDS]), Arc<DirectionalityTable>>,
    analyses: usize,
}

impl AnalysisCache {
    /// An empty cache.
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] when `params` does not validate.
    pub fn new(params: AnalysisParams, estimator: Estimator) -> Result<Self> {
        params.validate()?;
        Ok(AnalysisCache {
            params,
            estimator,
            emitters: HashMap::new(),
            brdfs: HashMap::new(),
            analyses: 0,
        })
    }

    /// The parameters every analysis of this cache uses.
    pub fn params(&self) -> &AnalysisParams {
        &self.params
    }

    /// The estimator every analysis of this cache uses.
    pub fn estimator(&self) -> Estimator {
        self.estimator
    }

    /// `alpha_D` of a `cos^n` emitter, analysed on first request.
    ///
    /// # Errors
    /// Whatever [`analyze_emitter`] returns (nothing is cached then).
    pub fn emitter(&mut self, e: &CosN) -> Result<f32> {
        let key = (e.exponent() + 0.0).to_bits();
        if let Some(&a) = self.emitters.get(&key) {
            return Ok(a);
        }
        let a = analyze_emitter(e, self.estimator, &self.params)?.alpha_d;
        self.analyses += 1;
        self.emitters.insert(key, a);
        Ok(a)
    }

    /// The table of a BRDF, analysed on first request; shared by `Arc`.
    ///
    /// # Errors
    /// Whatever [`analyze_brdf`] returns (nothing is cached then).
    pub fn brdf(&mut self, b: &Brdf) -> Result<Arc<DirectionalityTable>> {
        let key = b.param_bits();
        if let Some(t) = self.brdfs.get(&key) {
            return Ok(Arc::clone(t));
        }
        let t = Arc::new(analyze_brdf(b, self.estimator, &self.params)?);
        self.analyses += 1;
        self.brdfs.insert(key, Arc::clone(&t));
        Ok(t)
    }

    /// How many analyses actually ran (cache misses).
    pub fn analyses(&self) -> usize {
        self.analyses
    }

    /// Distinct functions held.
    pub fn len(&self) -> usize {
        self.emitters.len() + self.brdfs.len()
    }

    /// True when nothing has been analysed yet.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}
