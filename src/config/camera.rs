//! The camera: where it stands, how wide its image is, and its projection (the paper's
//! equirectangular 360-degree camera, optionally limited to an elevation band, or a pinhole).

use serde::{Deserialize, Serialize};

use super::{ConfigError, invalid, positive};

/// Which camera and its parameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Projection {
    /// Full sphere; `band_deg = Some((top, bottom))` renders only elevations from `top` down to
    /// `bottom` degrees (e.g. (1, -6)) at the full-sphere pixel pitch.
    Equirect { band_deg: Option<(f64, f64)> },
    /// Pinhole with horizontal field of view, looking at azimuth `yaw_deg`, elevation `pitch_deg`,
    /// turned about its view by `roll_deg` (positive: its right side down). Absent keys: 60
    /// degrees wide, looking along azimuth 0, level, upright. (`camera.look_at_m` sets the yaw
    /// and pitch instead.)
    Pinhole {
        #[serde(default = "pinhole_hfov_deg")]
        hfov_deg: f64,
        #[serde(default)]
        yaw_deg: f64,
        #[serde(default)]
        pitch_deg: f64,
        #[serde(default)]
        roll_deg: f64,
    },
}

fn pinhole_hfov_deg() -> f64 {
    60.0
}

/// The camera section of a scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CameraConfig {
    /// Height above mean sea level, m.
    pub height_m: f64,
    /// World horizontal position (x, z) of the camera, m. Geometry is built relative to it.
    pub position_m: [f64; 2],
    /// Image width in pixels (the full 360 degree width for the equirectangular camera).
    pub width: usize,
    /// Width / height of a pinhole image.
    pub aspect: f64,
    pub projection: Projection,
    /// A pinhole aimed at this point (world x, height above mean sea level, z; m) instead of
    /// by its yaw and pitch.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub look_at_m: Option<[f64; 3]>,
    /// A camera carried by an object (a bridge camera): it moves, pitches and rolls with it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mount: Option<Mount>,
}

/// Where an object carries the camera (`[camera.mount]`). The mount sets the camera's
/// `position_m` and `height_m` from the object's pose at the render's time; a pinhole's yaw,
/// pitch and roll are then taken in the object's frame (yaw 0 looks along its bow, roll 0 is
/// its deck's level), unless `look_at_m` aims it at a world point (a stabilised camera). A
/// panorama keeps the world's axes and only moves with the object.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Mount {
    /// The `name` of the `[[object]]` that carries the camera (`object-N` for an unnamed one).
    pub object: String,
    /// The camera's place in the object's frame: forward along its bow, up from its design
    /// waterline, to starboard; m (not scaled with the object's mesh).
    #[serde(default)]
    pub offset_m: [f64; 3],
}

impl Default for CameraConfig {
    fn default() -> Self {
        CameraConfig {
            height_m: 2.0,
            position_m: [0.0, 0.0],
            width: 2048,
            aspect: 16.0 / 9.0,
            projection: Projection::Equirect { band_deg: None },
            look_at_m: None,
            mount: None,
        }
    }
}

/// A pinhole's forward, right and up directions for its yaw, pitch and roll (radians): the
/// level right is (-sin yaw, 0, cos yaw); roll turns right and up about forward, right side
/// down for a positive roll.
pub fn pinhole_basis64(yaw: f64, pitch: f64, roll: f64) -> [glam::DVec3; 3] {
    let fwd = crate::equirect::direction64(pitch, yaw);
    let right = glam::DVec3::new(-yaw.sin(), 0.0, yaw.cos());
    let up = right.cross(fwd);
    if roll == 0.0 {
        return [fwd, right, up];
    }
    let (s, c) = roll.sin_cos();
    [fwd, c * right - s * up, s * right + c * up]
}

impl CameraConfig {
    /// The projection as rendered: a pinhole with `look_at_m` gets the yaw and pitch that
    /// look from the camera (at `position_m`, `height_m` up) at that point; otherwise the
    /// projection as given.
    pub fn aimed(&self) -> Projection {
        match (self.projection, self.look_at_m) {
            (
                Projection::Pinhole {
                    hfov_deg, roll_deg, ..
                },
                Some([x, y, z]),
            ) => {
                let d = glam::DVec3::new(
                    x - self.position_m[0],
                    y - self.height_m,
                    z - self.position_m[1],
                );
                Projection::Pinhole {
                    hfov_deg,
                    yaw_deg: d.z.atan2(d.x).to_degrees(),
                    pitch_deg: d.y.atan2(d.x.hypot(d.z)).to_degrees(),
                    roll_deg,
                }
            }
            (p, _) => p,
        }
    }

    /// The azimuths (degrees) under which a pinhole camera sees the sea: `(centre, half_width)`
    /// of the directions of its image that point below the horizontal. `None` when it sees the
    /// sea all round (the equirectangular camera; a pinhole whose image holds the nadir).
    ///
    /// The image plane maps linearly to directions (before normalisation), so the part of the
    /// image that looks down is the image rectangle clipped by a line, a convex polygon, and the
    /// horizontal components of its directions are another; unless that holds the origin (the
    /// nadir), its azimuths span less than a half turn and their extremes are at its corners.
    /// A horizontal field of view alone misses the corners of an image that looks down: their
    /// azimuths reach much further sideways.
    pub fn sea_azimuths_deg(&self) -> Option<(f64, f64)> {
        let Projection::Pinhole {
            hfov_deg,
            yaw_deg,
            pitch_deg,
            roll_deg,
        } = self.aimed()
        else {
            return None;
        };
        let (yaw, pitch) = (yaw_deg.to_radians(), pitch_deg.to_radians());
        let [fwd, right, up] = pinhole_basis64(yaw, pitch, roll_deg.to_radians());
        let tx = (0.5 * hfov_deg.to_radians()).tan();
        // The image's height over width, a pixel rounding's worth taller.
        let ty = tx * (1.0 / self.aspect + 1.0 / self.width as f64);
        let dir = |(sx, sy): (f64, f64)| fwd + sx * right + sy * up;
        // The image rectangle clipped to directions with y <= 0 (Sutherland-Hodgman, one edge).
        let rect = [(-tx, -ty), (tx, -ty), (tx, ty), (-tx, ty)];
        let mut poly: Vec<(f64, f64)> = Vec::new();
        for i in 0..4 {
            let (a, b) = (rect[i], rect[(i + 1) % 4]);
            let (ya, yb) = (dir(a).y, dir(b).y);
            if ya <= 0.0 {
                poly.push(a);
            }
            if (ya <= 0.0) != (yb <= 0.0) {
                let t = ya / (ya - yb);
                poly.push((a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)));
            }
        }
        if poly.is_empty() {
            // Looking up: no sea in view but whatever rises above the camera's height nearby.
            return Some((yaw_deg, 0.0));
        }
        // The nadir's place in the image plane: horizontal components both zero.
        let (a, b, c) = (fwd, right, up);
        // (A level camera's image plane is vertical: its nadir lies at infinity, det = 0.)
        let det = b.x * c.z - c.x * b.z;
        if det.abs() > 1e-12 {
            let sx0 = (-a.x * c.z + c.x * a.z) / det;
            let sy0 = (-b.x * a.z + a.x * b.z) / det;
            let inside = (0..poly.len()).all(|i| {
                let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
                (q.0 - p.0) * (sy0 - p.1) - (q.1 - p.1) * (sx0 - p.0) >= -1e-12
            });
            if inside && dir((sx0, sy0)).y < 0.0 {
                return None;
            }
        }
        let rel: Vec<f64> = poly
            .iter()
            .map(|&p| {
                let d = dir(p);
                let az = d.z.atan2(d.x) - yaw;
                (az + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
            })
            .collect();
        let lo = rel.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = rel.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if hi - lo > 170f64.to_radians() {
            return None;
        }
        Some((
            yaw_deg + (0.5 * (hi + lo)).to_degrees(),
            (0.5 * (hi - lo)).to_degrees(),
        ))
    }
}

impl CameraConfig {
    /// Checks every field; the first problem is returned with its name.
    pub fn validate(&self) -> Result<(), ConfigError> {
        if let Some(m) = &self.mount {
            if !m.offset_m.iter().all(|v| v.is_finite()) {
                return Err(invalid(
                    "camera.mount.offset_m",
                    "finite",
                    format!("{:?}", m.offset_m),
                ));
            }
            let free = CameraConfig::default();
            if self.position_m != free.position_m || self.height_m != free.height_m {
                return Err(invalid(
                    "camera.mount",
                    "alone: the mount sets camera.position_m and camera.height_m (leave them \
                     out)",
                    format!(
                        "position_m {:?}, height_m {}",
                        self.position_m, self.height_m
                    ),
                ));
            }
        }
        positive("camera.height_m", self.height_m)?;
        if !self.position_m.iter().all(|v| v.is_finite()) {
            return Err(invalid(
                "camera.position_m",
                "finite",
                format!("{:?}", self.position_m),
            ));
        }
        if !(2..=65_536).contains(&self.width) {
            return Err(invalid("camera.width", "in 2..=65536", self.width));
        }
        positive("camera.aspect", self.aspect)?;
        match self.projection {
            Projection::Equirect {
                band_deg: Some((top, bottom)),
            } => {
                if !(top.is_finite()
                    && bottom.is_finite()
                    && (-90.0..=90.0).contains(&top)
                    && (-90.0..=90.0).contains(&bottom)
                    && top > bottom)
                {
                    return Err(invalid(
                        "camera.projection.band_deg",
                        "(top, bottom) with 90 >= top > bottom >= -90",
                        format!("({top}, {bottom})"),
                    ));
                }
            }
            Projection::Pinhole {
                hfov_deg,
                yaw_deg,
                pitch_deg,
                roll_deg,
            } => {
                if !(hfov_deg > 0.0 && hfov_deg < 179.0) {
                    return Err(invalid(
                        "camera.projection.hfov_deg",
                        "in (0, 179)",
                        hfov_deg,
                    ));
                }
                if !yaw_deg.is_finite()
                    || !(-90.0..=90.0).contains(&pitch_deg)
                    || !(-180.0..=180.0).contains(&roll_deg)
                {
                    return Err(invalid(
                        "camera.projection",
                        "finite yaw, pitch in [-90, 90] and roll in [-180, 180]",
                        format!("yaw {yaw_deg}, pitch {pitch_deg}, roll {roll_deg}"),
                    ));
                }
                if let Some(p) = self.look_at_m {
                    let d = [
                        p[0] - self.position_m[0],
                        p[1] - self.height_m,
                        p[2] - self.position_m[1],
                    ];
                    if !p.iter().all(|c| c.is_finite()) || d.iter().all(|c| c.abs() < 1e-6) {
                        return Err(invalid(
                            "camera.look_at_m",
                            "a finite point other than the camera's",
                            format!("{p:?}"),
                        ));
                    }
                    if yaw_deg != 0.0 || pitch_deg != 0.0 {
                        return Err(invalid(
                            "camera.look_at_m",
                            "left out beside the pinhole's yaw_deg and pitch_deg, which it sets \
                             (keep one)",
                            format!("{p:?}"),
                        ));
                    }
                }
            }
            Projection::Equirect { band_deg: None } => {}
        }
        if let (Projection::Equirect { .. }, Some(p)) = (self.projection, self.look_at_m) {
            return Err(invalid(
                "camera.look_at_m",
                "given only for a pinhole camera (the panorama looks everywhere)",
                format!("{p:?}"),
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pinhole(hfov_deg: f64, yaw_deg: f64, pitch_deg: f64) -> CameraConfig {
        CameraConfig {
            projection: Projection::Pinhole {
                hfov_deg,
                yaw_deg,
                pitch_deg,
                roll_deg: 0.0,
            },
            ..CameraConfig::default()
        }
    }

    #[test]
    fn a_level_camera_sees_the_sea_over_its_horizontal_field_of_view() {
        let (c, h) = pinhole(60.0, 30.0, 0.0).sea_azimuths_deg().unwrap();
        assert!(
            (c - 30.0).abs() < 1e-9 && (h - 30.0).abs() < 1e-6,
            "{c} {h}"
        );
    }

    #[test]
    fn a_camera_looking_down_sees_further_sideways_at_its_corners() {
        // The case: 90 degrees wide, pitched 35 degrees down; a bottom corner looks
        // 63.6 degrees off the yaw, not 45.
        let (c, h) = pinhole(90.0, 45.0, -35.0).sea_azimuths_deg().unwrap();
        assert!((c - 45.0).abs() < 1e-9, "{c}");
        let corner = (1.0f64).atan2(35f64.to_radians().cos() - 0.5625 * 35f64.to_radians().sin());
        assert!((h - corner.to_degrees()).abs() < 0.2, "{h}");
        // Straight down, or steep enough that the nadir is in the image: all round.
        assert_eq!(pinhole(60.0, 0.0, -90.0).sea_azimuths_deg(), None);
        assert_eq!(pinhole(60.0, 0.0, -75.0).sea_azimuths_deg(), None);
        assert!(pinhole(60.0, 0.0, -60.0).sea_azimuths_deg().is_some());
        assert_eq!(CameraConfig::default().sea_azimuths_deg(), None);
    }

    /// `look_at_m` aims the pinhole from the camera's own place: a point 100 m along +z and
    /// 10 m below the camera gives yaw 90 and pitch -atan(0.1); without it the projection is
    /// as given; and a look-at beside an explicit yaw, on a panorama, or at the camera itself
    /// is refused, naming the key.
    #[test]
    fn look_at_sets_the_yaw_and_pitch() {
        let mut c = pinhole(40.0, 0.0, 0.0);
        c.position_m = [5.0, -3.0];
        c.height_m = 12.0;
        c.look_at_m = Some([5.0, 2.0, 97.0]);
        let Projection::Pinhole {
            yaw_deg, pitch_deg, ..
        } = c.aimed()
        else {
            panic!("a pinhole stays one");
        };
        assert!((yaw_deg - 90.0).abs() < 1e-9, "{yaw_deg}");
        assert!(
            (pitch_deg + 0.1f64.atan().to_degrees()).abs() < 1e-9,
            "{pitch_deg}"
        );
        c.validate().unwrap();
        assert_eq!(
            pinhole(40.0, 7.0, -3.0).aimed(),
            pinhole(40.0, 7.0, -3.0).projection
        );
        let refused = |c: CameraConfig| c.validate().unwrap_err().to_string();
        let mut both = c.clone();
        both.projection = pinhole(40.0, 7.0, 0.0).projection;
        assert!(refused(both).starts_with("camera.look_at_m"));
        let mut pano = c.clone();
        pano.projection = Projection::Equirect { band_deg: None };
        assert!(refused(pano).starts_with("camera.look_at_m"));
        let mut itself = c.clone();
        itself.look_at_m = Some([5.0, 12.0, -3.0]);
        assert!(refused(itself).starts_with("camera.look_at_m"));
    }
}
