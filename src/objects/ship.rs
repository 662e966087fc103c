//! The built-in ship: a Wigley hull, y = B/2 (1 - (2x/L)^2)(1 - (z/T)^2) below the waterline
//! (Wigley 1934; the standard test hull of naval hydrodynamics), vertical sides with the
//! waterline's half-breadth up to the deck, a flat deck, and a box deckhouse aft. In the
//! object's frame: bow along +x, up +y, the design waterline at y = 0, the hull's midship at
//! the origin. A closed surface, its triangles wound counter-clockwise seen from outside; the
//! deckhouse is a part of its own colour (`ship.deckhouse_albedo`).

use super::LocalMesh;
use crate::config::ShipConfig;

/// Stations along the length and waterlines down to the keel: 48 x 8 quads a side below the
/// waterline (the hull's curvature reads smooth at a few hundred pixels across).
const STATIONS: usize = 48;
const WATERLINES: usize = 8;

/// The ship's mesh.
pub fn wigley_ship(s: &ShipConfig) -> LocalMesh {
    let (l, b, t, f) = (s.length_m, s.beam_m, s.draft_m, s.freeboard_m);
    let mut m = LocalMesh::default();
    let x_of = |i: usize| (i as f64 / STATIONS as f64 * 2.0 - 1.0) * 0.5 * l;
    let half = |i: usize, zeta: f64| {
        let xi = i as f64 / STATIONS as f64 * 2.0 - 1.0;
        0.5 * b * (1.0 - xi * xi) * (1.0 - zeta * zeta)
    };
    // Heights of the rows of one side, from the deck down to the keel: the deck, the
    // waterline, then the waterlines below it (zeta = j / WATERLINES).
    let mut rows: Vec<(f64, f64)> = vec![(f, 0.0)];
    rows.extend((0..=WATERLINES).map(|j| {
        let zeta = j as f64 / WATERLINES as f64;
        (-zeta * t, zeta)
    }));
    for side in [1.0, -1.0] {
        let base = m.positions.len() as u32;
        for &(y, zeta) in &rows {
            for i in 0..=STATIONS {
                m.positions.push([x_of(i), y, side * half(i, zeta)]);
            }
        }
        let w = STATIONS as u32 + 1;
        for r in 0..rows.len() as u32 - 1 {
            for i in 0..STATIONS as u32 {
                let a = base + r * w + i;
                let (b1, c, d) = (a + 1, a + w, a + w + 1);
                // outward: +z on the starboard (+z) side, -z on the other
                if side > 0.0 {
                    m.triangles.push([a, d, b1]);
                    m.triangles.push([a, c, d]);
                } else {
                    m.triangles.push([a, b1, d]);
                    m.triangles.push([a, d, c]);
                }
            }
        }
    }
    // The deck: strips between the two sides' deck edges.
    let base = m.positions.len() as u32;
    for i in 0..=STATIONS {
        m.positions.push([x_of(i), f, half(i, 0.0)]);
        m.positions.push([x_of(i), f, -half(i, 0.0)]);
    }
    for i in 0..STATIONS as u32 {
        let (a, a2, b1, b2) = (
            base + 2 * i,
            base + 2 * i + 1,
            base + 2 * i + 2,
            base + 2 * i + 3,
        );
        m.triangles.push([a, b1, a2]);
        m.triangles.push([a2, b1, b2]);
    }
    if s.deckhouse_m > 0.0 {
        let (x0, x1) = (-0.38 * l, -0.18 * l);
        let hz = 0.35 * b;
        m.parts.push((m.triangles.len(), s.deckhouse_albedo));
        m.push_box([x0, f, -hz], [x1, f + s.deckhouse_m, hz]);
    }
    m
}

impl LocalMesh {
    /// Appends the closed box between corners `lo` and `hi`.
    pub fn push_box(&mut self, lo: [f64; 3], hi: [f64; 3]) {
        let base = self.positions.len() as u32;
        for k in 0..8 {
            self.positions.push([
                if k & 1 == 0 { lo[0] } else { hi[0] },
                if k & 2 == 0 { lo[1] } else { hi[1] },
                if k & 4 == 0 { lo[2] } else { hi[2] },
            ]);
        }
        // corner k has bit 0 = x, bit 1 = y, bit 2 = z; each face counter-clockwise outside
        for q in [
            [0, 4, 6, 2], // -x
            [1, 3, 7, 5], // +x
            [0, 1, 5, 4], // -y
            [2, 6, 7, 3], // +y
            [0, 2, 3, 1], // -z
            [4, 5, 7, 6], // +z
        ] {
            let q = q.map(|c: u32| base + c);
            self.triangles.push([q[0], q[1], q[2]]);
            self.triangles.push([q[0], q[2], q[3]]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The signed volume enclosed by `triangles` of `m` (divergence theorem).
    fn volume(m: &LocalMesh, triangles: &[[u32; 3]]) -> f64 {
        triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                let cross = [
                    b[1] * c[2] - b[2] * c[1],
                    b[2] * c[0] - b[0] * c[2],
                    b[0] * c[1] - b[1] * c[0],
                ];
                (a[0] * cross[0] + a[1] * cross[1] + a[2] * cross[2]) / 6.0
            })
            .sum()
    }

    /// The hull's volume: below the waterline the Wigley hull displaces the closed form
    /// (4/9) L B T (the integral of (1 - xi^2)(1 - zeta^2) over the unit square, times L B T),
    /// above it the vertical sides hold (2/3) L B F; the mesh's, by the divergence theorem over
    /// its closed surface, is within the discretisation's 1 %. Winding outward makes the
    /// signed volume positive.
    #[test]
    fn the_wigley_hull_displaces_four_ninths_of_its_box() {
        let s = ShipConfig {
            deckhouse_m: 0.0,
            ..ShipConfig::default()
        };
        let m = wigley_ship(&s);
        let hull = volume(&m, &m.triangles);
        let closed_form = 4.0 / 9.0 * s.length_m * s.beam_m * s.draft_m
            + s.freeboard_m * s.length_m * s.beam_m * 2.0 / 3.0;
        assert!(
            (hull / closed_form - 1.0).abs() < 0.01,
            "mesh volume {hull:.2} m^3, closed form {closed_form:.2}"
        );
        // the deckhouse's box adds its own volume, with outward faces too
        let with = wigley_ship(&ShipConfig::default());
        let extra = volume(&with, &with.triangles[m.triangles.len()..]);
        let s2 = ShipConfig::default();
        let box_volume = 0.2 * s2.length_m * 0.7 * s2.beam_m * s2.deckhouse_m;
        assert!(
            (extra / box_volume - 1.0).abs() < 1e-9,
            "{extra} vs {box_volume}"
        );
    }
}
