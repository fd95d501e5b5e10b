//! What a run counted (docs/method.md, "What a run reports"): photons
//! emitted, stored, re-emitted, split rates per depth, whether a bound was
//! hit, and how long it took.

use super::config::Mode;
use super::counts::LightPlan;

/// Counters of one bounce depth (depth 0 = the photons leaving the lights).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct DepthStats {
    /// Photons that hit a surface.
    pub hits: u64,
    /// Photons that left the scene.
    pub escaped: u64,
    /// Children created at those hits.
    pub children: u64,
    /// Hits where the per-hit cap bound.
    pub capped: u64,
    /// Photons stored at this depth.
    pub stored: u64,
    /// Luminance of the power stored at this depth.
    pub stored_power_luminance: f64,
    /// Wall time of the wave.
    pub seconds: f64,
}

/// Counts and timings of a run.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct TraceReport {
    /// The mode.
    pub mode: Mode,
    /// `N_MAX` of the run.
    pub n_max: u64,
    /// Photons emitted, all lights.
    pub emitted: u64,
    /// Photons emitted per light.
    pub emitted_per_light: Vec<u64>,
    /// Photons stored, all depths.
    pub stored: u64,
    /// Photons stored at their first hit.
    pub stored_primary: u64,
    /// Photons re-emitted from first hits (the paper's Fig. 8).
    pub reemitted_first_hit: u64,
    /// Mean children per hit at each depth (the paper's Fig. 9b).
    pub split_rate_by_depth: Vec<f64>,
    /// Counters per depth.
    pub depths: Vec<DepthStats>,
    /// True when the memory budget stopped splitting or the run.
    pub budget_bound: bool,
    /// Hits where the per-hit cap bound, all depths.
    pub capped_hits: u64,
    /// Density control: photons stored.
    pub density_accepted: u64,
    /// Density control: photons whose power went to their neighbours.
    pub density_rejected: u64,
    /// Sum of the stored photons' RGB power.
    pub stored_power: [f64; 3],
    /// Rays cast (every photon of every wave: hits plus escapes).
    pub rays: u64,
    /// Rays cast per second of the whole trace, in millions: the tracer's
    /// throughput, shading and storage included.
    pub mrays_per_s: f64,
    /// The same in rays per second.
    pub rays_per_s: f64,
    /// Wall time of the whole trace.
    pub trace_s: f64,
    /// Wall time of wave 0 (emission and first hits): the primary map's trace.
    pub trace_primary_s: f64,
    /// The kernels that found the hits (`None` for a caster whose hits do
    /// not depend on the CPU): with the same settings, Embree version, kernel
    /// set and [`math`](Self::math), the map is the same on any host.
    pub kernels: Option<crate::isa::Kernels>,
    /// The C maths library's variant on the tracing host.
    pub math: Option<crate::isa::MathVariant>,
    /// What importance in the counts did (`None` without it: the paper's
    /// runs report exactly what they did before).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub importance: Option<ImportanceReport>,
}

/// The importance pass and its effect on a run.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct ImportanceReport {
    /// Seconds of the importance pass (camera walk and freezing the grid).
    pub pass_s: f64,
    /// Cells of the frozen grid.
    pub cells: usize,
    /// Each light's emission alpha_I (from its pilot photons).
    pub emission_alpha_i: Vec<f32>,
    /// `A_ref`, the adjoint alpha_I divides by (the pilot photons' mean at
    /// their first hits, weighted by the lights' power; 0: the read cells'
    /// mean was used).
    pub reference_adjoint: f32,
    /// Photons not stored because nothing reads them where they landed.
    pub unread: u64,
}

impl TraceReport {
    pub(super) fn new(
        mode: Mode,
        n_max: u64,
        plans: &[LightPlan],
        kernels: Option<crate::isa::Kernels>,
    ) -> Self {
        TraceReport {
            mode,
            n_max,
            emitted: plans.iter().fold(0u64, |a, p| a.saturating_add(p.photons)),
            emitted_per_light: plans.iter().map(|p| p.photons).collect(),
            stored: 0,
            stored_primary: 0,
            reemitted_first_hit: 0,
            split_rate_by_depth: Vec::new(),
            depths: Vec::new(),
            budget_bound: false,
            capped_hits: 0,
            density_accepted: 0,
            density_rejected: 0,
            stored_power: [0.0; 3],
            rays: 0,
            mrays_per_s: 0.0,
            rays_per_s: 0.0,
            trace_s: 0.0,
            trace_primary_s: 0.0,
            kernels,
            math: crate::isa::MathVariant::host(),
            importance: None,
        }
    }

    pub(super) fn depth_mut(&mut self, depth: usize) -> &mut DepthStats {
        if self.depths.len() <= depth {
            self.depths.resize(depth + 1, DepthStats::default());
        }
        &mut self.depths[depth]
    }

    /// Totals from the stored photons' exact per-depth power sums
    /// (`Quantizer::power_sums`: count and RGB power by depth).
    pub(super) fn finish(&mut self, by_depth: &[(u64, [f64; 3])]) {
        let mut power = [0.0f64; 3];
        for d in &mut self.depths {
            d.stored = 0;
            d.stored_power_luminance = 0.0;
        }
        for (depth, &(n, p)) in by_depth.iter().enumerate() {
            for c in 0..3 {
                power[c] += p[c];
            }
            let d = self.depth_mut(depth);
            d.stored = n;
            d.stored_power_luminance = crate::sampling::luminance_f64(p);
        }
        self.stored = by_depth.iter().map(|d| d.0).sum();
        self.stored_power = power;
        self.stored_primary = self.depths.first().map_or(0, |d| d.stored);
        self.reemitted_first_hit = self.depths.first().map_or(0, |d| d.children);
        self.capped_hits = self.depths.iter().map(|d| d.capped).sum();
        self.trace_primary_s = self.depths.first().map_or(0.0, |d| d.seconds);
        self.rays = self.depths.iter().map(|d| d.hits + d.escaped).sum();
        if self.trace_s > 0.0 {
            self.rays_per_s = self.rays as f64 / self.trace_s;
            self.mrays_per_s = self.rays_per_s / 1e6;
        }
        self.split_rate_by_depth = self
            .depths
            .iter()
            .filter(|d| d.hits > 0)
            .map(|d| d.children as f64 / d.hits as f64)
            .collect();
    }
}
