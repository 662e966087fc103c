//! How a scene is rendered: samples, seeds, threads, the shading normals (the paper's
//! "with/without normal mapping"), path length, the tracing backend, and the water's optics.

use serde::{Deserialize, Serialize};

/// Where the shading normal comes from (DESIGN.md, Normal modes).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum NormalMode {
    /// Barycentric interpolation of the vertex normals (the paper's "without normal mapping").
    Vertex,
    /// Eq. 7 from the ocean layers at the interpolated texture coordinate.
    #[default]
    Mapped,
    /// Beyond the paper: the waves the ray's footprint resolves give the mapped normal; the
    /// waves below it are a Gaussian slope distribution (a rough dielectric) whose covariance
    /// is the realization's own, with the sun sampled at every rough hit (docs/filtered.md).
    Filtered,
    /// The surface's own normal: on the exact surface (`render.surface = "exact"`) its
    /// tangent plane, so no shading normal can disagree with the geometry and the wrong-side
    /// question never arises (`compare --against truth` renders its truth so); on a mesh the
    /// flat triangle's.
    Geometric,
}

super::choice!(NormalMode { Vertex => "vertex", Mapped => "mapped", Filtered => "filtered", Geometric => "geometric" });

/// Which lobe filtered normals give the waves below the footprint (docs/filtered.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum FilterLobe {
    /// Normals drawn by area from the unresolved slopes, as the points of a pixel have them,
    /// each shaded as a mapped normal is (the same Fresnel split and wrong-side policy): the
    /// mapped render's own statistics, so it converges to the same image.
    #[default]
    Mapped,
    /// Visible normals with Smith's masking (Walter et al. 2007; Heitz 2014): the microfacet
    /// model of a rough surface, which loses the light masked at grazing angles that mapped
    /// normals keep.
    Smith,
}

super::choice!(FilterLobe { Mapped => "mapped", Smith => "smith" });

/// What the integrator does when the shading normal disagrees with the triangle it shades:
/// when it faces away from the incoming ray, or would send the reflected or refracted ray to
/// the wrong side of the triangle (DESIGN.md, Normal modes; measured in docs/accuracy.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum WrongSide {
    /// Shading normal facing away: use the geometric one; wrong-side direction: mirror it
    /// across the triangle's plane, keeping its weight.
    Mirror,
    /// Shading normal facing away: flip it to face the ray; wrong-side direction: mirror it.
    Flip,
    /// Bend the shading normal just enough that the reflection leaves above the triangle
    /// (Cycles' ensure_valid_reflection, after Keller et al. 2017); a refraction still on the
    /// wrong side is mirrored. Conserves energy, as production renderers do.
    Bend,
    /// End the branch that would leave on the wrong side, and the path at a shading normal
    /// facing away (Mitsuba's strictNormals): no wrong-side light, at the cost of energy. The
    /// default because against a truth no policy touches (the exact displaced surface) it is
    /// the closer of it and `Bend` on three of the paper's five cases and on their mean, for
    /// both the paper's baseline and its coarse mesh (docs/accuracy.md, "The default policy,
    /// over four ocean seeds"); not for its ratio.
    #[default]
    Terminate,
}

super::choice!(WrongSide { Mirror => "mirror", Flip => "flip", Bend => "bend", Terminate => "terminate" });

/// Which BVH traces the scene: Embree when this build has it, else the Rust BVH.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Backend {
    /// Debian's Embree through the C shim.
    Embree,
    /// The pure-Rust BVH (src/accel/bvh).
    Rust,
}

super::choice!(Backend { Embree => "embree", Rust => "rust" });

impl Default for Backend {
    fn default() -> Self {
        if cfg!(feature = "embree") {
            Backend::Embree
        } else {
            Backend::Rust
        }
    }
}

/// What the rays meet: the tessellation's triangles, or the displaced ocean itself inside them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum SurfaceKind {
    /// The LOD mesh's triangles (the paper's).
    #[default]
    Mesh,
    /// Beyond the paper: the first crossing of the summed layers' displaced surface, found
    /// inside the prisms of the coarse mesh's triangles (wave hiding without a fine mesh;
    /// docs/exact.md). Needs `mapped` normals and bilinear reads.
    Exact,
}

super::choice!(SurfaceKind { Mesh => "mesh", Exact => "exact" });

/// The render section of a scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RenderConfig {
    pub spp: u32,
    /// Seed of the Monte Carlo samples.
    pub seed: u64,
    /// Seed of the ocean: which realization of the sea state (kept apart from `seed`, so the
    /// same sea can be rendered with independent noise).
    pub ocean_seed: u64,
    /// Worker threads for tessellation, Embree and tracing (0 = all cores).
    pub threads: usize,
    pub normals: NormalMode,
    /// Filtered normals: the std of the Gaussian footprint the waves are seen through, in ray
    /// cone widths (a pixel's width at the hit). The default, 1 / sqrt(12), is the std of the
    /// pixel's own box; wider filters more of the waves into the rough lobe (less noise, less
    /// sub-pixel detail), narrower fewer (docs/filtered.md).
    pub filter_width: f32,
    /// Filtered normals: the lobe of the waves below the footprint.
    pub filter_lobe: FilterLobe,
    /// Filtered normals: the sun's samples at a rough hit seen from the air whose lobe may
    /// reflect the sun (one at its faint edge, none where it reflects none), spread evenly over
    /// its disc, one shadow ray among them (docs/filtered.md, "The sun's samples").
    pub sun_samples: u32,
    /// Most segments (rays) in one path (the paper: 10).
    pub max_segments: u32,
    /// Hits up to this depth branch into both reflection and refraction; deeper ones choose one.
    pub branch_depth: u32,
    pub backend: Backend,
    /// What the rays meet (the mesh, or the exact displaced surface inside it).
    pub surface: SurfaceKind,
    /// What to do when the shading normal disagrees with the triangle it shades.
    pub wrong_side: WrongSide,
    /// Embree: build a compact BVH (`RTC_SCENE_FLAG_COMPACT`): paper-high's render peak 3.15 ->
    /// 2.22 GB and a 1.6x faster build, for 15-18 % slower traversal (3-5 % of a render);
    /// false for the fastest tracing when memory allows (docs/performance.md).
    pub compact_bvh: bool,
    /// Embree: how the ocean mesh's whole cells are handed over, as grids or as triangles
    /// (the same triangles either way); `auto` picks grids where the build they save
    /// outweighs the tracing they slow (docs/performance.md, "Grids").
    pub embree_geometry: EmbreeGeometry,
    /// The PNG preview's exposure in stops (EV): radiance times 2^exposure goes through the
    /// tone curve. `None` (written `"auto"`, the default) maps each image's median luminance to
    /// mid grey; an animation takes its first frame's. The EXR is never scaled.
    #[serde(with = "exposure")]
    pub exposure: Option<f32>,
    /// How the EXR is compressed: not at all (the default), or losslessly with PIZ or ZIP.
    pub exr_compression: ExrCompression,
    /// Layers for training data written beside the image as further EXR channels, from each
    /// pixel's centre ray (docs/objects.md, "Layers for training data").
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub aovs: Vec<Aov>,
}

/// How a render's EXR is stored (`render.exr_compression`, `--exr-compression`). Every choice
/// is lossless. A path-traced image is mostly noise in its low mantissa bits, which no
/// lossless coder removes: on the default render PIZ keeps 78 % of the bytes and costs the
/// whole run a tenth of its time (docs/performance.md, "Output").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum ExrCompression {
    /// The samples as they are: the fastest to write and to read.
    #[default]
    None,
    /// OpenEXR's wavelet and Huffman coder, the smallest files for noisy images.
    Piz,
    /// Deflate over blocks of 16 rows (OpenEXR's ZIP).
    Zip,
}

super::choice!(ExrCompression { None => "none", Piz => "piz", Zip => "zip" });

/// How Embree is given the ocean mesh (`render.embree_geometry`, `--embree-geometry`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum EmbreeGeometry {
    /// Grids when the mesh has more triangles than an estimate of the samples' break-even
    /// ([`EmbreeGeometry::grids_for`]), triangles otherwise.
    #[default]
    Auto,
    /// Blocks of whole cells as grids (`RTC_GEOMETRY_TYPE_GRID`), the rest as triangles: a
    /// BVH over far fewer primitives, built some 8x faster in less memory.
    Grids,
    /// Every cell as its two triangles.
    Triangles,
}

super::choice!(EmbreeGeometry { Auto => "auto", Grids => "grids", Triangles => "triangles" });

impl EmbreeGeometry {
    /// Triangles per camera sample above which `auto` takes grids. Measured
    /// (docs/performance.md, "Grids"): grids save some 0.19 us of build per triangle
    /// (paper-high) and cost up to some 0.02 us of trace per camera sample (paper-low's large
    /// cells; nothing measurable on paper-high), so they pay above 0.02 / 0.19.
    pub const AUTO_TRIANGLES_PER_SAMPLE: f64 = 0.1;

    /// Whether a mesh of `triangles` traced by `samples` camera samples is built as grids.
    pub fn grids_for(self, triangles: usize, samples: u64) -> bool {
        match self {
            EmbreeGeometry::Grids => true,
            EmbreeGeometry::Triangles => false,
            EmbreeGeometry::Auto => {
                triangles as f64 > Self::AUTO_TRIANGLES_PER_SAMPLE * samples as f64
            }
        }
    }
}

/// A layer of training data (`render.aovs`, `--aov`): what each pixel's centre ray meets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Aov {
    /// `Z`: the distance to the first hit, m (+inf for the sky).
    Depth,
    /// `N.X N.Y N.Z`: the shading normal there (the water's air side up, an object's facing
    /// the camera; 0 for the sky).
    Normal,
    /// `id`: -1 the sky, 0 the water, k the k-th object of the file.
    Id,
}

super::choice!(Aov { Depth => "depth", Normal => "normal", Id => "id" });

/// `render.exposure` in a file: a number of stops, or `"auto"`.
mod exposure {
    use serde::de::Error;
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &Option<f32>, s: S) -> Result<S::Ok, S::Error> {
        match v {
            Some(stops) => s.serialize_f32(*stops),
            None => s.serialize_str("auto"),
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f32>, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Given {
            Stops(f32),
            Word(String),
        }
        match Given::deserialize(d)? {
            Given::Stops(stops) => Ok(Some(stops)),
            Given::Word(w) if w == "auto" => Ok(None),
            Given::Word(w) => Err(D::Error::custom(format!(
                "`auto` or a number of stops, got `{w}`"
            ))),
        }
    }
}

/// Parses `--exposure`: `auto` or a number of stops.
pub fn parse_exposure(s: &str) -> Result<Option<f32>, String> {
    if s == "auto" {
        return Ok(None);
    }
    match s.parse::<f32>() {
        Ok(v) if v.is_finite() && v.abs() <= MAX_EXPOSURE_STOPS => Ok(Some(v)),
        _ => Err(format!(
            "`auto` or a number of stops within +-{MAX_EXPOSURE_STOPS} (got `{s}`)"
        )),
    }
}

/// The largest |render.exposure|, stops: 2^64 covers any radiance an f32 holds.
pub const MAX_EXPOSURE_STOPS: f32 = 64.0;

impl Default for RenderConfig {
    fn default() -> Self {
        RenderConfig {
            spp: 16,
            seed: 1,
            ocean_seed: 1,
            threads: 0,
            normals: NormalMode::Mapped,
            filter_width: FILTER_WIDTH_BOX,
            filter_lobe: FilterLobe::Mapped,
            sun_samples: 8,
            max_segments: 10,
            branch_depth: 3,
            backend: Backend::default(),
            surface: SurfaceKind::Mesh,
            wrong_side: WrongSide::default(),
            compact_bvh: true,
            embree_geometry: EmbreeGeometry::Auto,
            exposure: None,
            exr_compression: ExrCompression::None,
            aovs: Vec::new(),
        }
    }
}

/// The std of a pixel's box in its widths, 1 / sqrt(12): the default `render.filter_width`.
pub const FILTER_WIDTH_BOX: f32 = 0.288_675_13;

/// Optical properties of the water.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Water {
    /// Refractive index relative to air.
    pub ior: f32,
    /// Absorption coefficients, 1/m, per linear RGB channel.
    pub absorption: [f32; 3],
    /// Remote-sensing reflectance R_rs = L_w / E_d, 1/sr, per channel: the water-leaving
    /// radiance L_w per unit downwelling irradiance E_d. What a downward ray that never meets
    /// the surface again returns is R_rs times the sky's irradiance (`Water::upwelling` in `crate::render::water`), so
    /// the sea's body colour keeps its proportion to any sky, in any units.
    pub upwelling_rrs: [f32; 3],
}

impl Default for Water {
    fn default() -> Self {
        // Pure-water absorption at 600 / 550 / 450 nm for R / G / B (Pope & Fry 1997: 0.2224,
        // 0.0565, 0.00922 1/m); R_rs of clear open ocean in the red, green and blue (about
        // 0.0003, 0.002, 0.008 1/sr; cf. Morel & Maritorena 2001).
        Water {
            ior: 1.333,
            absorption: [0.2224, 0.0565, 0.00922],
            upwelling_rrs: [0.0003, 0.002, 0.008],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::EmbreeGeometry;

    /// `auto` takes grids for paper-high at the sizes it is rendered at, not at thousands of
    /// samples a pixel, and not for paper-low unless the render is tiny; the other two
    /// choices are what they say.
    #[test]
    fn auto_takes_grids_for_large_meshes_against_their_samples() {
        let (high, low) = (22_341_600, 25_520);
        let samples = |w: u64, spp: u64| w * (w / 2) * spp;
        assert!(EmbreeGeometry::Auto.grids_for(high, samples(1024, 16)));
        assert!(EmbreeGeometry::Auto.grids_for(high, samples(2048, 64)));
        assert!(!EmbreeGeometry::Auto.grids_for(high, samples(2048, 256)));
        assert!(!EmbreeGeometry::Auto.grids_for(low, samples(1024, 4)));
        assert!(!EmbreeGeometry::Triangles.grids_for(high, 1));
        assert!(EmbreeGeometry::Grids.grids_for(low, u64::MAX));
    }
}
