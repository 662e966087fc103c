//! The ocean surface as the sum of layers with non-integer-ratio extents (paper eqs. 5-6), each
//! holding its share of every |k| (`OceanParams::partition`: shares sum to one, so no energy
//! is counted twice), and its evaluation at any nominal
//! position x: the surface point X(x, t) = x + D + y h (eq. 4), the normal of eq. 7 from the
//! summed FFT gradients, and the Jacobian J of the horizontal map x -> x + D, which is <= 0 where
//! choppiness folds the surface over itself (Tessendorf 2001, "choppy waves").
//!
//! The camera's world position is kept in f64 and reduced modulo each layer's extent once per
//! [`Sampler`]; samples take camera-relative f32 coordinates, so a camera 100 km out reads the
//! ocean with the precision of one near the origin.
//!
//! Normal orientation: with dX/dx = (1 + dDx/dx, dh/dx, dDz/dx) and dX/dz = (dDx/dz, dh/dz,
//! 1 + dDz/dz), n = dX/dz x dX/dx points to +y on a flat sea in this right-handed (x, y, z)
//! frame (eq. 7's dX/dx x dX/dz would point down). Its unnormalised y component equals J, so
//! the normal tips below the horizon exactly where the surface is folded.

use std::sync::OnceLock;
use std::time::Instant;

use super::layer::{
    FIELD_COUNT, FieldPlanes, Layer, SLOPES, Slopes, Texel, add_texel, field, slopes,
};
use super::levels::Levels;
use super::slopes::{SlopeSource, SurfaceSlopes};
use super::spectrum::Spectrum;
use super::{Interp, MAX_LAYERS, OceanError, OceanParams};

/// A sum of FFT layers, immutable once built (so `Send + Sync` and shared by all render threads).
pub struct Surface {
    layers: Vec<Layer>,
    spectrum: Option<Spectrum>,
    params: OceanParams,
    seed: u64,
    amplitude_scale: f64,
    seconds: f64,
    /// [`Surface::sampled`], computed on first use (48 ms for the default ocean: a million reads
    /// spread over every layer's texels) and kept until the time changes.
    sampled: OnceLock<Sampled>,
    /// [`Surface::slopes`], computed on first use (35 ms for the default ocean: a pass over
    /// every layer's amplitudes) and kept until the time changes.
    slopes: OnceLock<SurfaceSlopes>,
    /// [`Surface::read_slopes`], likewise.
    read_slopes: OnceLock<SurfaceSlopes>,
    /// [`Surface::levels`], built on first use (what filtered normals read) and kept until the
    /// time changes.
    levels: OnceLock<Levels>,
    /// [`Surface::summary`], computed on first use (62 ms for the default ocean: band integrals
    /// of the spectrum and passes over every texel) and kept until the time changes.
    summary: OnceLock<OceanSummary>,
}

/// The surface at one nominal position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// h, m.
    pub height: f32,
    /// (Dx, Dz), m.
    pub disp: [f32; 2],
    /// Unit normal of eq. 7, +y up, in the flat-earth frame.
    pub normal: [f32; 3],
    /// J = (1 + dDx/dx)(1 + dDz/dz) - (dDx/dz)^2; <= 0 where the surface folds.
    pub jacobian: f32,
}

impl Sample {
    /// The flat sea.
    pub const FLAT: Sample = Sample {
        height: 0.0,
        disp: [0.0, 0.0],
        normal: [0.0, 1.0, 0.0],
        jacobian: 1.0,
    };

    /// From the summed fields of all layers.
    #[inline]
    pub fn from_fields(f: &Texel) -> Sample {
        let (normal, jacobian) = normal_from_slopes(slopes(f));
        Sample {
            height: f[field::H],
            disp: [f[field::DX], f[field::DZ]],
            normal,
            jacobian,
        }
    }

    /// X(x, t) of eq. 4, camera-relative: [u + Dx, h, v + Dz].
    #[inline]
    pub fn position(&self, u: f32, v: f32) -> [f32; 3] {
        [u + self.disp[0], self.height, v + self.disp[1]]
    }
}

/// The unit normal of eq. 7 and the Jacobian J from the summed derivative fields.
#[inline]
pub(super) fn normal_from_slopes(g: Slopes) -> ([f32; 3], f32) {
    let at = |f: usize| g[f - SLOPES.start];
    let (hx, hz) = (at(field::DH_DX), at(field::DH_DZ));
    let (a, c) = (1.0 + at(field::DDX_DX), 1.0 + at(field::DDZ_DZ));
    let b = at(field::DDX_DZ);
    // dX/dz x dX/dx with dX/dx = (a, hx, b), dX/dz = (b, hz, c)
    let n = [hz * b - c * hx, c * a - b * b, b * hx - hz * a];
    let len2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    let normal = if len2 > 0.0 {
        let inv = 1.0 / len2.sqrt();
        [n[0] * inv, n[1] * inv, n[2] * inv]
    } else {
        [0.0, 1.0, 0.0]
    };
    (normal, n[1])
}

/// Reads a [`Surface`] around one camera origin. Cheap to copy; one per thread is fine.
#[derive(Clone, Copy)]
pub struct Sampler<'a> {
    pub(super) layers: &'a [Layer],
    /// Per layer: the origin modulo the layer's extent, in grid units.
    pub(super) origin: [[f64; 2]; MAX_LAYERS],
    pub(super) interp: Interp,
    /// The layers' low-passed levels, which filtered normals read ([`Sampler::with_levels`]).
    pub(super) levels: Option<&'a Levels>,
}

impl Sampler<'_> {
    /// The surface at camera-relative nominal position (u, v) = (x, z) in metres.
    #[inline]
    pub fn sample(&self, u: f32, v: f32) -> Sample {
        Sample::from_fields(&self.fields(u, v))
    }

    /// The unit normal at (u, v), bit-identical to `self.sample(u, v).normal` without the
    /// position and Jacobian (what normal mapping needs at every hit). All eight fields are
    /// interpolated even so: a texel's eight floats are two 4-wide vectors, and reading only
    /// the five derivatives was scalar code and more instructions (callgrind).
    #[inline]
    pub fn normal(&self, u: f32, v: f32) -> [f32; 3] {
        normal_from_slopes(slopes(&self.fields(u, v))).0
    }

    /// The unit normals at the points `uv` into `out`, each bit for bit `self.normal(u, v)`:
    /// up to eight points at a time, whose cells and weights are computed together and whose
    /// normals are independent (what normal mapping needs for a batch of hits).
    pub fn normals(&self, uv: &[[f32; 2]], out: &mut [[f32; 3]]) {
        assert_eq!(uv.len(), out.len(), "one normal per point");
        if self.interp == Interp::Bicubic {
            for (n, &[u, v]) in out.iter_mut().zip(uv) {
                *n = self.normal(u, v);
            }
            return;
        }
        // Eight lanes at a time; four for a batch's last four or fewer (small batches are
        // common: a render of few samples per pixel, the rays leaving hits).
        let (mut uv, mut out) = (uv, out);
        while !uv.is_empty() {
            let k = uv.len().min(8);
            let (now, rest) = uv.split_at(k);
            let (into, rest_out) = std::mem::take(&mut out).split_at_mut(k);
            if k > 4 {
                self.normals_in_lanes::<8>(now, into);
            } else {
                self.normals_in_lanes::<4>(now, into);
            }
            (uv, out) = (rest, rest_out);
        }
    }

    /// [`Sampler::normals`] of up to `LANES` points, bilinear or variance-preserving.
    #[inline]
    fn normals_in_lanes<const LANES: usize>(&self, uv: &[[f32; 2]], out: &mut [[f32; 3]]) {
        let sum = self.fields_in_lanes::<LANES>(uv);
        for (n, s) in out.iter_mut().zip(&sum) {
            *n = normal_from_slopes(slopes(s)).0;
        }
    }

    /// The samples at the points `uv` into `out`, each bit for bit `self.sample(u, v)`, eight
    /// points at a time as [`Sampler::normals`] reads them (what a tessellation needs at every
    /// vertex: its scalar reads were two fifths of paper-high's).
    pub fn samples(&self, uv: &[[f32; 2]], out: &mut [Sample]) {
        assert_eq!(uv.len(), out.len(), "one sample per point");
        if self.interp == Interp::Bicubic {
            for (s, &[u, v]) in out.iter_mut().zip(uv) {
                *s = self.sample(u, v);
            }
            return;
        }
        for (now, into) in uv.chunks(8).zip(out.chunks_mut(8)) {
            let sum = self.fields_in_lanes::<8>(now);
            for (s, f) in into.iter_mut().zip(&sum) {
                *s = Sample::from_fields(f);
            }
        }
    }

    /// The eight summed fields at up to `LANES` points `uv` (the lanes past them hold the
    /// fields at the origin), bilinear or variance-preserving, each bit for bit
    /// [`Sampler::fields`].
    #[inline]
    fn fields_in_lanes<const LANES: usize>(&self, uv: &[[f32; 2]]) -> [Texel; LANES] {
        let count = uv.len();
        let (mut u, mut v) = ([0.0f32; LANES], [0.0f32; LANES]);
        for (l, p) in uv.iter().enumerate() {
            (u[l], v[l]) = (p[0], p[1]);
        }
        let mut sum = [[0.0f32; FIELD_COUNT]; LANES];
        let preserve = self.interp == Interp::VariancePreserving;
        for (layer, o) in self.layers.iter().zip(&self.origin) {
            let inv = layer.inv_dx();
            let px = std::array::from_fn(|l| o[0] + u[l] as f64 * inv);
            let pz = std::array::from_fn(|l| o[1] + v[l] as f64 * inv);
            layer.add_bilinear_lanes(&px, &pz, count, preserve, &mut sum);
        }
        sum
    }

    /// The eight summed fields at (u, v), in [`field`] order.
    #[inline]
    pub fn fields(&self, u: f32, v: f32) -> Texel {
        self.fields_f64(u as f64, v as f64)
    }

    /// [`Sampler::fields`] at a nominal position held in f64 (the exact surface's root finder
    /// works below an f32's millimetre at 10 km); bit for bit `fields(u, v)` where the
    /// position is an f32.
    #[inline]
    pub fn fields_f64(&self, u: f64, v: f64) -> Texel {
        self.fields_f64_at(u, v, &super::slopes::ALL_WAVES)
    }

    /// Per layer: the camera origin modulo the layer's extent, in grid units (a nominal
    /// position u reads grid coordinate `origin + u / dx`).
    pub fn grid_origins(&self) -> &[[f64; 2]] {
        &self.origin[..self.layers.len()]
    }

    /// The layers read, in the order of [`Sampler::grid_origins`].
    pub fn layers(&self) -> &[Layer] {
        self.layers
    }
}

/// Every layer's fields at time `t`, one layer after another, each on every core, in one set of
/// planes (run side by side, the two big default layers sometimes ended up on one thread in
/// turn, rayon's stealing, 1.8x the time).
fn compute_fields(layers: &mut [Layer], t: f64) {
    let mut planes = FieldPlanes::default();
    for l in layers {
        l.compute_fields_in(t, &mut planes);
    }
}

/// How far a read's value can exceed the largest value over the grid points, as a factor: the
/// largest sum of the read's absolute weights (bilinear 1; Catmull-Rom 1.25 per axis, at a
/// fraction of one half); None for the variance-preserving read, which has no such bound.
fn read_reach(interp: Interp) -> Option<f64> {
    match interp {
        Interp::Bilinear | Interp::Prefiltered => Some(1.0),
        Interp::Bicubic => Some(1.5625),
        Interp::VariancePreserving => None,
    }
}

fn layer_seed(seed: u64, i: usize) -> u64 {
    seed ^ (i as u64 + 1).wrapping_mul(0xD1B5_4A32_D192_ED03)
}

impl Surface {
    /// Builds every layer at `params.time_s` and scales the amplitudes so the
    /// realization's RMS height is `params.rms_m` when set.
    pub fn new(params: &OceanParams, seed: u64) -> Result<Surface, OceanError> {
        params.validate()?;
        let start = Instant::now();
        let spectrum = Spectrum::new(params);
        let partition = params.partition();
        let mut layers = params
            .layers
            .iter()
            .enumerate()
            .map(|(i, l)| {
                Layer::drawn(
                    &spectrum,
                    l.size_m,
                    l.n,
                    partition.support(i),
                    &|k| partition.weight(i, k),
                    params.choppiness,
                    layer_seed(seed, i),
                    params.time_s,
                )
            })
            .collect::<Result<Vec<_>, _>>()?;
        // the realization's variance from the amplitudes (Parseval), so the RMS scale applies
        // to them before the transforms rather than to every texel after
        let variance: f64 = layers
            .iter()
            .map(|l| l.spectral_height_variance(params.time_s))
            .sum();
        let mut amplitude_scale = 1.0;
        if let Some(target) = params.rms_target() {
            if variance.is_nan() || variance <= 0.0 {
                // The sea state, not the RMS target, is what is wrong: a wind too light or a
                // fetch too short puts the spectrum's peak far below the finest texels.
                let peak_m = 2.0 * std::f64::consts::PI * crate::ocean::spectrum::G
                    / (spectrum.omega_p * spectrum.omega_p);
                let finest_m = params
                    .layers
                    .iter()
                    .map(|l| 2.0 * l.size_m / l.n as f64)
                    .fold(f64::INFINITY, f64::min);
                return Err(OceanError::invalid(
                    "ocean.wind_speed",
                    format!(
                        "strong enough, over ocean.fetch_km = {}, to put wave energy into the layers' bands (the spectrum peaks at a wavelength of {peak_m:.3e} m, the finest layer resolves {finest_m:.3} m; raise the wind or the fetch, or add a finer layer)",
                        params.fetch_km
                    ),
                    params.wind_speed,
                ));
            }
            amplitude_scale = target / variance.sqrt();
            layers.iter_mut().for_each(|l| l.scale(amplitude_scale));
        }
        for l in &mut layers {
            l.set_prefilter(params.interp == Interp::Prefiltered);
        }
        compute_fields(&mut layers, params.time_s);
        let mut surface = Surface {
            layers,
            spectrum: Some(spectrum),
            params: params.clone(),
            seed,
            amplitude_scale,
            seconds: 0.0,
            sampled: OnceLock::new(),
            slopes: OnceLock::new(),
            read_slopes: OnceLock::new(),
            levels: OnceLock::new(),
            summary: OnceLock::new(),
        };
        surface.seconds = start.elapsed().as_secs_f64();
        Ok(surface)
    }

    /// No waves: height 0, normal +y, J = 1 everywhere.
    pub fn flat() -> Surface {
        Surface {
            layers: Vec::new(),
            spectrum: None,
            params: OceanParams {
                rms_m: None,
                choppiness: 0.0,
                layers: Vec::new(),
                ..OceanParams::default()
            },
            seed: 0,
            amplitude_scale: 0.0,
            seconds: 0.0,
            sampled: OnceLock::new(),
            slopes: OnceLock::new(),
            read_slopes: OnceLock::new(),
            levels: OnceLock::new(),
            summary: OnceLock::new(),
        }
    }

    /// Re-evaluates every layer at time `t` (eq. 2); the amplitude scale is kept.
    pub fn set_time(&mut self, t: f64) -> Result<(), OceanError> {
        if !t.is_finite() {
            return Err(OceanError::invalid("ocean.time_s", "finite", t));
        }
        compute_fields(&mut self.layers, t);
        self.params.time_s = t;
        self.sampled = OnceLock::new();
        self.slopes = OnceLock::new();
        self.read_slopes = OnceLock::new();
        self.levels = OnceLock::new();
        self.summary = OnceLock::new();
        Ok(())
    }

    /// A sampler for a camera at world horizontal position `origin` = (x, z), metres.
    pub fn sampler(&self, origin: [f64; 2]) -> Sampler<'_> {
        self.sampler_with(origin, self.params.interp)
    }

    /// As [`Surface::sampler`] with an explicit interpolation.
    pub fn sampler_with(&self, origin: [f64; 2], interp: Interp) -> Sampler<'_> {
        let mut o = [[0.0; 2]; MAX_LAYERS];
        for (slot, l) in o.iter_mut().zip(&self.layers) {
            let s = l.size_m();
            *slot = [
                origin[0].rem_euclid(s) * l.inv_dx(),
                origin[1].rem_euclid(s) * l.inv_dx(),
            ];
        }
        Sampler {
            layers: &self.layers,
            origin: o,
            interp,
            levels: None,
        }
    }

    /// Bytes of the layers' gridded fields (what sampling the ocean reads).
    pub fn bytes(&self) -> usize {
        self.layers
            .iter()
            .map(|l| std::mem::size_of_val(l.fields()))
            .sum()
    }

    pub fn layers(&self) -> &[Layer] {
        &self.layers
    }
    pub fn params(&self) -> &OceanParams {
        &self.params
    }
    /// The seed the layers' amplitudes were drawn from.
    pub fn seed(&self) -> u64 {
        self.seed
    }
    pub fn spectrum(&self) -> Option<&Spectrum> {
        self.spectrum.as_ref()
    }

    /// Fraction of the summed surface with J <= 0: exactly 0 where the layers' largest
    /// strains prove that no read with the surface's interpolation (`params.interp`, what
    /// [`Surface::sampler`] reads) can fold ([`Surface::cannot_fold`]), else estimated on a
    /// jittered STATS_GRID^2 grid over the coarsest period.
    pub fn folded_fraction(&self) -> f64 {
        if self.cannot_fold() {
            0.0
        } else {
            self.sampled().folded_fraction
        }
    }

    /// True when J > 0 at every point a read with `params.interp` can return:
    /// [`Surface::fold_bound`] is above a
    /// margin that covers f32 rounding in the reads and in J.
    pub fn cannot_fold(&self) -> bool {
        const MARGIN: f64 = 1e-3;
        self.layers.is_empty() || self.fold_bound().is_some_and(|j| j > MARGIN)
    }

    /// The slope covariance by band of every layer at the surface's time, what filtered normals
    /// split at each hit ([`SurfaceSlopes`]) under the `smith` lobe, computed once and shared by
    /// every render of it.
    pub fn slopes(&self) -> &SurfaceSlopes {
        self.slopes
            .get_or_init(|| SurfaceSlopes::new(self, SlopeSource::Spectrum))
    }

    /// [`Surface::slopes`] as [`Surface::sampler`] reads them (`params.interp`), what the
    /// `mapped` lobe splits: the normals mapped normals would have.
    pub fn read_slopes(&self) -> &SurfaceSlopes {
        self.read_slopes
            .get_or_init(|| SurfaceSlopes::new(self, SlopeSource::Read(self.params.interp)))
    }

    /// Every layer's low-passed levels ([`Levels`]), built on first use and shared by every
    /// render of the surface at its time.
    pub fn levels(&self) -> &Levels {
        self.levels.get_or_init(|| Levels::new(&self.layers))
    }

    /// Whether [`Surface::levels`] are built (the memory check counts them until they are).
    pub fn levels_built(&self) -> bool {
        self.levels.get().is_some()
    }

    /// A lower bound on J = (1 + dDx/dx)(1 + dDz/dz) - (dDx/dz)^2 over every read of the summed
    /// surface, from each layer's largest strains over its grid points. A bilinear read is a
    /// convex blend of four texels, so no field it returns is larger than the field's largest
    /// value over the grid points; a Catmull-Rom read's weights sum to at most 1.25^2 in
    /// absolute value ([`read_reach`]). With A, C and B the sums over the layers of those bounds
    /// for dDx/dx, dDz/dz and dDx/dz, J >= (1 - A)(1 - C) - B^2 wherever A, C < 1. None where
    /// A or C reaches 1, or the read is variance-preserving (it rescales by its own blend).
    pub fn fold_bound(&self) -> Option<f64> {
        let reach = read_reach(self.params.interp)?;
        let [a, c, b] = self.layers.iter().fold([0.0f64; 3], |sum, l| {
            let m = l.grid_stats().max_strain;
            std::array::from_fn(|i| sum[i] + reach * m[i] as f64)
        });
        (a < 1.0 && c < 1.0).then_some((1.0 - a) * (1.0 - c) - b * b)
    }

    /// RMS height of the realization: sqrt of the sum of the layers' grid variances, m (as
    /// [`OceanSummary::realization_rms_m`], without computing the summary).
    pub fn realization_rms_m(&self) -> f64 {
        self.layers
            .iter()
            .map(Layer::height_variance)
            .sum::<f64>()
            .sqrt()
    }
}

#[path = "surface_summary.rs"]
mod summary;
use summary::Sampled;
pub use summary::{LayerSummary, OceanSummary, PartitionSummary};

#[cfg(test)]
#[path = "surface_stats_tests.rs"]
mod stats_tests;
#[cfg(test)]
#[path = "surface_tests.rs"]
mod tests;
