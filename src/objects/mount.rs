//! A camera carried by an object (`[camera.mount]`, a bridge or mast camera): its place and,
//! for a pinhole, its aim follow the object's pose at the render's time, so an animation's
//! camera heaves, pitches and rolls with the ship it stands on.

use glam::DVec3;

use super::{LocalMesh, ObjectError, Pose};
use crate::config::camera::pinhole_basis64;
use crate::config::{CameraConfig, ObjectConfig, Projection};
use crate::ocean::Surface;

/// The camera `camera` with its mount resolved on the sea of `ocean` (at the ocean's time):
/// `position_m` and `height_m` are the mount point's, a pinhole's yaw, pitch and roll (given
/// in the object's frame) are turned into the world's, and the mount is gone. A camera
/// without a mount is returned as it is.
pub fn mounted_camera(
    camera: &CameraConfig,
    objects: &[ObjectConfig],
    ocean: &Surface,
) -> Result<CameraConfig, ObjectError> {
    let Some(mount) = &camera.mount else {
        return Ok(camera.clone());
    };
    let (_, object) = (objects.iter().enumerate())
        .find(|(k, o)| o.display_name(*k) == mount.object)
        .ok_or_else(|| ObjectError::Mount(mount.object.clone()))?;
    let local = LocalMesh::of(object)?;
    let pose = Pose::of(
        object,
        &local,
        &ocean.sampler(object.position_m),
        [0.0, 0.0],
    );
    let at = pose.place(DVec3::from(mount.offset_m));
    let mut resolved = camera.clone();
    resolved.mount = None;
    resolved.position_m = [object.position_m[0] + at.x, object.position_m[1] + at.z];
    resolved.height_m = at.y;
    if let (
        Projection::Pinhole {
            hfov_deg,
            yaw_deg,
            pitch_deg,
            roll_deg,
        },
        None,
    ) = (camera.projection, camera.look_at_m)
    {
        let [fwd, right, _] = pinhole_basis64(
            yaw_deg.to_radians(),
            pitch_deg.to_radians(),
            roll_deg.to_radians(),
        );
        let (yaw, pitch, roll) = yaw_pitch_roll(pose.turn(fwd), pose.turn(right));
        resolved.projection = Projection::Pinhole {
            hfov_deg,
            yaw_deg: yaw.to_degrees(),
            pitch_deg: pitch.to_degrees(),
            roll_deg: roll.to_degrees(),
        };
    }
    Ok(resolved)
}

/// The yaw, pitch and roll (radians) whose [`pinhole_basis64`] has forward `fwd` and right
/// `right` (unit, orthogonal).
fn yaw_pitch_roll(fwd: DVec3, right: DVec3) -> (f64, f64, f64) {
    let yaw = fwd.z.atan2(fwd.x);
    let pitch = fwd.y.clamp(-1.0, 1.0).asin();
    let level = DVec3::new(-yaw.sin(), 0.0, yaw.cos());
    let up = level.cross(fwd);
    // right = cos(roll) level - sin(roll) up
    let roll = (-right.dot(up)).atan2(right.dot(level));
    (yaw, pitch, roll)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Yaw, pitch and roll survive the round trip through a basis, and a basis turned about the
    /// vertical keeps its pitch and roll.
    #[test]
    fn a_basis_gives_back_its_angles() {
        for &(yaw, pitch, roll) in &[
            (0.3, -0.2, 0.1),
            (-2.9, 0.6, -1.2),
            (1.0, 0.0, 3.0),
            (0.0, -1.3, 0.0),
        ] {
            let [f, r, _] = pinhole_basis64(yaw, pitch, roll);
            let (y, p, q) = yaw_pitch_roll(f, r);
            assert!(
                (y - yaw).abs() < 1e-12 && (p - pitch).abs() < 1e-12 && (q - roll).abs() < 1e-12,
                "{yaw} {pitch} {roll} -> {y} {p} {q}"
            );
        }
    }
}
