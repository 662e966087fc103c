//! Normals from the flat-sea frame of the ocean layers into the curved-earth frame at a hit
//! (DESIGN.md, Curved earth), one at a time and in lanes.

use glam::Vec3;

/// Rotates a vector given in the flat-sea frame at camera-relative nominal position (u, v) into
/// the curved-earth frame there: the local vertical at horizontal distance r is tilted by
/// r / R away from the camera's nadir (DESIGN.md, Curved earth).
#[inline]
pub fn tilt_to_earth(u: f32, v: f32, earth_radius_m: f64, n: Vec3) -> Vec3 {
    let r = (u * u + v * v).sqrt();
    if r == 0.0 || !earth_radius_m.is_finite() {
        return n;
    }
    let theta = (r as f64 / earth_radius_m) as f32;
    let (s, c) = if theta < TILT_SERIES_MAX {
        tilt_series(theta)
    } else {
        theta.sin_cos()
    };
    Vec3::from(rotate_tilt(u, v, r, s, c, n.to_array()))
}

/// Angles below this take two Taylor terms, exact in f32 there and much cheaper than sin_cos
/// (this runs at every mapped hit); out to the horizon theta stays under 1e-3 rad.
const TILT_SERIES_MAX: f32 = 1e-2;

/// (sin theta, cos theta) for theta < [`TILT_SERIES_MAX`].
#[inline]
fn tilt_series(theta: f32) -> (f32, f32) {
    let t2 = theta * theta;
    (theta * (1.0 - t2 / 6.0), 1.0 - 0.5 * t2 * (1.0 - t2 / 12.0))
}

/// Rotation of `n` by the angle with sine `s` and cosine `c` about the horizontal axis
/// a = (v, 0, -u) / r (Rodrigues' formula): n c + (a x n) s + a (a . n) (1 - c), written out
/// in glam's order of operations (the renders stayed bit for bit the same) so that lanes of it
/// compile to vector code.
#[inline]
fn rotate_tilt(u: f32, v: f32, r: f32, s: f32, c: f32, n: [f32; 3]) -> [f32; 3] {
    let (ax, ay, az) = (v / r, 0.0f32, -u / r);
    let [nx, ny, nz] = n;
    let cross = [ay * nz - ny * az, az * nx - nz * ax, ax * ny - nx * ay];
    let dot = ax * nx + ay * ny + az * nz;
    let k = 1.0 - c;
    [
        nx * c + cross[0] * s + ax * dot * k,
        ny * c + cross[1] * s + ay * dot * k,
        nz * c + cross[2] * s + az * dot * k,
    ]
}

/// [`tilt_to_earth`] of every `n[i]` at `uv[i]`, bit for bit: points out to the series' reach
/// are rotated together, branch-free, in vector code; the rest (the nadir, a flat earth,
/// beyond the series) one at a time.
pub fn tilt_to_earth_many(uv: &[[f32; 2]], earth_radius_m: f64, n: &mut [Vec3]) {
    const LANES: usize = 8;
    assert_eq!(uv.len(), n.len(), "one position per vector");
    let finite = earth_radius_m.is_finite();
    for (uv, n) in uv.chunks(LANES).zip(n.chunks_mut(LANES)) {
        // Lanes past the chunk rotate +y at the origin, and are not written back. Components
        // are kept apart (one array per coordinate): the layout vector code wants.
        let (mut u, mut v) = ([0.0f32; LANES], [0.0f32; LANES]);
        let mut flat = [[0.0f32; LANES], [1.0; LANES], [0.0; LANES]];
        for (l, (p, n)) in uv.iter().zip(&*n).enumerate() {
            (u[l], v[l]) = (p[0], p[1]);
            (flat[0][l], flat[1][l], flat[2][l]) = (n.x, n.y, n.z);
        }
        let mut series = [false; LANES];
        let mut tilted = [[0.0f32; LANES]; 3];
        for l in 0..LANES {
            let r = (u[l] * u[l] + v[l] * v[l]).sqrt();
            let theta = (r as f64 / earth_radius_m) as f32;
            // (A NaN radius fails the `theta <` test: the scalar path returns its rotation.)
            series[l] = r != 0.0 && theta < TILT_SERIES_MAX;
            let (s, c) = tilt_series(theta);
            let t = rotate_tilt(u[l], v[l], r, s, c, [flat[0][l], flat[1][l], flat[2][l]]);
            (tilted[0][l], tilted[1][l], tilted[2][l]) = (t[0], t[1], t[2]);
        }
        for (l, n) in n.iter_mut().enumerate() {
            *n = if series[l] && finite {
                Vec3::new(tilted[0][l], tilted[1][l], tilted[2][l])
            } else {
                tilt_to_earth(u[l], v[l], earth_radius_m, *n)
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn earth_tilt_turns_up_towards_the_local_vertical() {
        let r = 6_371_000.0;
        let n = tilt_to_earth(5000.0, 0.0, r, Vec3::Y);
        // 5 km along +x the local vertical leans 5000/R radians towards +x
        assert!((n.x - (5000.0 / r) as f32).abs() < 1e-7 && (n.length() - 1.0).abs() < 1e-6);
        assert_eq!(tilt_to_earth(0.0, 0.0, r, Vec3::Y), Vec3::Y);
        let n = tilt_to_earth(0.0, -3000.0, r, Vec3::Y);
        assert!(n.z < 0.0 && n.x.abs() < 1e-9);
    }

    #[test]
    fn earth_tilt_in_lanes_is_the_tilt_one_at_a_time() {
        let mut uv = Vec::new();
        let mut n = Vec::new();
        for i in 0..37u64 {
            let h = crate::rng::splitmix64(i);
            let f = |k: u32| ((h >> k) & 0xFFFF) as f32 / 65536.0 - 0.5;
            // out to 150 km: past the series' reach (63.7 km on the earth; 10 m on a planet
            // of 1 km, where the series would be wrong at the 300 m scale)
            let scale = [3.0e5, 600.0, 30.0][i as usize % 3];
            uv.push([f(0) * scale, f(16) * scale]);
            n.push(Vec3::new(f(32), 1.0, f(48)).normalize());
        }
        uv.extend([
            [0.0, 0.0],
            [1.0e-30, 0.0],
            [f32::NAN, 2.0],
            [f32::INFINITY, 0.0],
        ]);
        n.extend([Vec3::Y, Vec3::X, Vec3::Y, Vec3::Z]);
        for r in [6_371_000.0, 1000.0, f64::INFINITY] {
            let mut lanes = n.clone();
            tilt_to_earth_many(&uv, r, &mut lanes);
            for ((&[u, v], &n), t) in uv.iter().zip(&n).zip(lanes) {
                let one = tilt_to_earth(u, v, r, n);
                // (every NaN alike: which of two NaN operands an instruction passes on, and so
                // the result's sign, follows the operands' order, which a compiler may swap in a
                // commutative operation, as the x86-64-v3 build's three-operand forms do)
                let bits = |v: Vec3| {
                    v.to_array()
                        .map(|x| if x.is_nan() { f32::NAN } else { x }.to_bits())
                };
                assert_eq!(bits(t), bits(one), "R {r} at ({u}, {v})");
            }
        }
    }
}
