//! Objects on the sea (`[[object]]` in a scene file): a mesh (the built-in Wigley ship or a
//! Wavefront OBJ / PLY file), where it stands, which way it heads, how large it is, whether it
//! floats on the waves, and its colour. The meshes themselves are read and placed by
//! [`crate::objects`]; this is the plain data and its checks.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use super::{ConfigError, invalid, positive};

/// The built-in ship's mesh name (`mesh = "ship"`).
pub const BUILT_IN_SHIP: &str = "ship";

/// One object of the scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ObjectConfig {
    /// A name for reports (default `object-N`, N from 1 in file order).
    pub name: Option<String>,
    /// `"ship"` (the built-in Wigley hull with a deckhouse, sized by `[object.ship]`) or the
    /// path of a `.obj` or `.ply` mesh, relative to the scene file. A file's mesh is in metres
    /// with +y up and its bow (its forward direction) along +x; its design waterline is y = 0.
    pub mesh: PathBuf,
    /// World horizontal position (x, z) of the mesh's origin, m (as `camera.position_m`).
    pub position_m: [f64; 2],
    /// The azimuth the mesh's +x axis points to, degrees (azimuth 0 is +x, 90 is +z: the
    /// pinhole camera's `yaw_deg`).
    pub heading_deg: f64,
    /// Uniform scale of the mesh.
    pub scale: f64,
    /// Height of the mesh's origin above mean sea level, m, when it does not float.
    pub height_m: f64,
    /// Float on the sea: heave, pitch and roll from a least-squares plane through the surface
    /// under the hull at the render's time (docs/objects.md). `height_m` is then ignored.
    pub float: bool,
    /// What the surface is: Lambertian (`diffuse`), a GGX conductor (`metal`) or a rough GGX
    /// dielectric that reflects and refracts (`glass`).
    pub material: Material,
    /// Linear RGB in [0, 1]: the diffuse reflectance, a metal's reflectance at normal
    /// incidence, or the share of light glass lets through at each crossing of its surface (1:
    /// white or clear, as a furnace test wants).
    pub albedo: [f64; 3],
    /// A metal's or glass's GGX roughness alpha (0.001 mirror-like to 1 very rough).
    pub roughness: f64,
    /// Glass's index of refraction (1.5 window glass, 1.31 ice).
    pub ior: f64,
    /// The built-in ship's dimensions (`mesh = "ship"` only).
    pub ship: ShipConfig,
}

impl Default for ObjectConfig {
    fn default() -> Self {
        ObjectConfig {
            name: None,
            mesh: PathBuf::from(BUILT_IN_SHIP),
            position_m: [0.0, 0.0],
            heading_deg: 0.0,
            scale: 1.0,
            height_m: 0.0,
            float: true,
            material: Material::Diffuse,
            albedo: [0.5, 0.5, 0.5],
            roughness: 0.3,
            ior: 1.5,
            ship: ShipConfig::default(),
        }
    }
}

/// An object's surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Material {
    /// Lambertian: light reflected alike into every direction.
    #[default]
    Diffuse,
    /// A rough conductor: GGX microfacets, Smith masking, Schlick's Fresnel (paint with a sheen,
    /// steel, aluminium).
    Metal,
    /// A rough dielectric: GGX microfacets that reflect and refract by the Fresnel equations
    /// (glass, ice, clear plastic). Its mesh must be closed and wound outward.
    Glass,
}

super::choice!(Material { Diffuse => "diffuse", Metal => "metal", Glass => "glass" });

/// The built-in ship: a Wigley hull y = B/2 (1 - (2x/L)^2)(1 - (z/T)^2) (the standard test hull
/// of naval hydrodynamics) with vertical sides up to the deck and a deckhouse aft.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ShipConfig {
    /// Length L at the waterline, m.
    pub length_m: f64,
    /// Beam B at the waterline, m.
    pub beam_m: f64,
    /// Draft T (waterline to keel), m.
    pub draft_m: f64,
    /// Height of the deck above the waterline, m.
    pub freeboard_m: f64,
    /// Height of the deckhouse above the deck, m (0: none).
    pub deckhouse_m: f64,
    /// The deckhouse's diffuse reflectance (the hull takes the object's `albedo`).
    pub deckhouse_albedo: [f64; 3],
}

impl Default for ShipConfig {
    /// A 40 m coaster: the Wigley model's proportions (L/B = 10, B/T = 1.6) widened to a
    /// working hull's L/B = 5.
    fn default() -> Self {
        ShipConfig {
            length_m: 40.0,
            beam_m: 8.0,
            draft_m: 2.5,
            freeboard_m: 2.0,
            deckhouse_m: 5.0,
            deckhouse_albedo: [0.7, 0.7, 0.7],
        }
    }
}

impl ObjectConfig {
    /// Whether the mesh is the built-in ship.
    pub fn is_built_in_ship(&self) -> bool {
        self.mesh.as_os_str() == BUILT_IN_SHIP
    }

    /// The name reports use: `name`, or `object-N` for the `index`-th object (from 0).
    pub fn display_name(&self, index: usize) -> String {
        self.name
            .clone()
            .unwrap_or_else(|| format!("object-{}", index + 1))
    }

    /// Checks every field; `at` is `object[N]` as the file counts them (from 0).
    pub fn validate(&self, at: &str) -> Result<(), ConfigError> {
        let field = |f: &str| format!("{at}.{f}");
        if !self.is_built_in_ship() {
            let ext = self
                .mesh
                .extension()
                .and_then(|e| e.to_str())
                .map(str::to_ascii_lowercase);
            if !matches!(ext.as_deref(), Some("obj" | "ply")) {
                return Err(invalid(
                    &field("mesh"),
                    "\"ship\" or a file ending in .obj or .ply",
                    self.mesh.display(),
                ));
            }
        }
        if !self.position_m.iter().all(|v| v.is_finite()) {
            return Err(invalid(
                &field("position_m"),
                "finite",
                format!("{:?}", self.position_m),
            ));
        }
        for (f, v) in [
            ("heading_deg", self.heading_deg),
            ("height_m", self.height_m),
        ] {
            if !v.is_finite() {
                return Err(invalid(&field(f), "finite", v));
            }
        }
        if !(self.scale > 0.0 && self.scale <= 1e4) {
            return Err(invalid(&field("scale"), "in (0, 10000]", self.scale));
        }
        for (f, albedo) in [
            ("albedo", self.albedo),
            ("ship.deckhouse_albedo", self.ship.deckhouse_albedo),
        ] {
            if !albedo.iter().all(|a| (0.0..=1.0).contains(a)) {
                return Err(invalid(
                    &field(f),
                    "three reflectances in [0, 1]",
                    format!("{albedo:?}"),
                ));
            }
        }
        if !(self.roughness >= 0.001 && self.roughness <= 1.0) {
            return Err(invalid(
                &field("roughness"),
                "in [0.001, 1]",
                self.roughness,
            ));
        }
        if self.material == Material::Glass
            && self.is_built_in_ship()
            && self.ship.deckhouse_m > 0.0
        {
            return Err(invalid(
                &field("material"),
                "a closed surface for glass: the built-in ship's deckhouse is a box of its own \
                 standing on the deck (set ship.deckhouse_m = 0)",
                "glass",
            ));
        }
        if !(self.ior >= 1.0 && self.ior <= 4.0) {
            return Err(invalid(&field("ior"), "in [1, 4]", self.ior));
        }
        let s = &self.ship;
        for (f, v) in [
            ("ship.length_m", s.length_m),
            ("ship.beam_m", s.beam_m),
            ("ship.draft_m", s.draft_m),
            ("ship.freeboard_m", s.freeboard_m),
        ] {
            positive(&field(f), v)?;
        }
        if !(s.deckhouse_m >= 0.0 && s.deckhouse_m.is_finite()) {
            return Err(invalid(
                &field("ship.deckhouse_m"),
                "finite and >= 0",
                s.deckhouse_m,
            ));
        }
        if s.beam_m > s.length_m {
            return Err(invalid(
                &field("ship.beam_m"),
                "at most ship.length_m",
                s.beam_m,
            ));
        }
        Ok(())
    }
}
