//! What a render counts: rays, hits, shortcuts taken, wrong-side events and the cost of the
//! mapped normals, summed over threads and passes.

use serde::Serialize;

/// Per-render counts, summed over threads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct Counters {
    /// Rays whose closest hit was searched for: by the BVH, or for `predicted` of them on
    /// their pixel's predicted triangle.
    pub rays: u64,
    /// Ocean hits shaded.
    pub hits: u64,
    /// Samples whose radiance was NaN or infinite (dropped by the guard).
    pub nan: u64,
    /// Camera rays below the horizon that met no water (see [`TraceSettings::must_hit_below_y`]).
    pub escaped_below_horizon: u64,
    /// Rays spawned at a hit that met their own triangle again (self-intersection). Should be 0.
    pub self_hits: u64,
    /// Reflected or refracted rays the shading normal sent to the wrong side of the triangle.
    pub wrong_side: u64,
    /// Hits where the shading normal faced away from the incoming ray.
    pub backfacing_shading: u64,
    /// Shading normals bent by the `bend` policy.
    pub bent: u64,
    /// Branches (or, at a normal facing away, whole hits) ended by the `terminate` policy.
    pub terminated: u64,
    /// Paths cut at `max_segments` while still bouncing.
    pub truncated: u64,
    /// Rays in the water known not to meet the surface again, so not traced.
    pub skipped: u64,
    /// Rays in the air leaving a hit upwards more steeply than any slope of the mesh, so
    /// never meeting it again: not traced. Absent from pass files written before it.
    #[serde(default)]
    pub skipped_rising: u64,
    /// Rays leaving upwards from above the mesh's highest vertex, so never meeting it: not
    /// traced (the camera's upper half, for one). Absent from pass files written before it.
    #[serde(default)]
    pub skipped_above: u64,
    /// Camera rays whose hit was found on their pixel's predicted triangle, without the BVH
    /// (counted in `rays` too; see [`SceneRef::predict_camera_prim`]). Absent from pass files
    /// written before it.
    #[serde(default)]
    pub predicted: u64,
    /// Rays traced through the pixels' centres to predict those triangles (not in `rays`;
    /// every pass traces its pixels' again, so merged passes sum them). Absent from pass files
    /// written before it.
    #[serde(default)]
    pub prediction_rays: u64,
    /// Mapped normals evaluated (`normal_evals`), in `normal_batches` calls, each a batch of
    /// hits. Of every 64 calls, one is timed alone (`normal_timed` intervals, `normal_timed_ns`
    /// in all, over `normal_timed_points` normals) and one is timed followed by a second,
    /// discarded evaluation of the same normals (`normal_timed_twice`, `..._ns`, `..._points`).
    /// See [`Counters::normal_map_thread_seconds`] (applied to a render's own counters: a
    /// merge adds up the passes' estimates). Absent from pass files written before the
    /// batches: `normal_batches` and the `_points`.
    pub normal_evals: u64,
    #[serde(default)]
    pub normal_batches: u64,
    pub normal_timed: u64,
    pub normal_timed_ns: u64,
    #[serde(default)]
    pub normal_timed_points: u64,
    #[serde(default)]
    pub normal_timed_twice: u64,
    #[serde(default)]
    pub normal_timed_twice_ns: u64,
    #[serde(default)]
    pub normal_timed_twice_points: u64,
    /// Filtered normals: hits shaded with a rough lobe (the rest resolve every wave), those
    /// of them that sampled the sun (`sun_hits`; the rest reflect none of it), the sun's
    /// samples they took (`sun_samples`), the shadow rays traced for them
    /// (`sun_rays`; the rest rose clear of the mesh) and those the sea blocked. Absent from
    /// pass files written before them.
    #[serde(default)]
    pub rough_hits: u64,
    #[serde(default)]
    pub sun_hits: u64,
    #[serde(default)]
    pub sun_samples: u64,
    #[serde(default)]
    pub sun_rays: u64,
    #[serde(default)]
    pub sun_occluded: u64,
    /// Objects: rays traced against their structure (those crossing their bounds; the rays
    /// they take from the sea still count in the sea's counts, `rays` or a `skipped_*`),
    /// object hits shaded (each samples the sun in the air), and the sun's shadow rays (the
    /// sea's or theirs) that an object blocked. Absent from pass files written before them.
    #[serde(default)]
    pub object_rays: u64,
    #[serde(default)]
    pub object_hits: u64,
    #[serde(default)]
    pub sun_object_occluded: u64,
    /// Rays inside a glass object that met none of its surface before the path's last segment
    /// (an open or inward-wound mesh lets them out): they return nothing.
    #[serde(default)]
    pub object_leaks: u64,
}

impl std::ops::AddAssign for Counters {
    fn add_assign(&mut self, o: Counters) {
        self.rays += o.rays;
        self.hits += o.hits;
        self.nan += o.nan;
        self.escaped_below_horizon += o.escaped_below_horizon;
        self.self_hits += o.self_hits;
        self.wrong_side += o.wrong_side;
        self.backfacing_shading += o.backfacing_shading;
        self.bent += o.bent;
        self.terminated += o.terminated;
        self.truncated += o.truncated;
        self.skipped += o.skipped;
        self.skipped_rising += o.skipped_rising;
        self.skipped_above += o.skipped_above;
        self.predicted += o.predicted;
        self.prediction_rays += o.prediction_rays;
        self.normal_evals += o.normal_evals;
        self.normal_batches += o.normal_batches;
        self.normal_timed += o.normal_timed;
        self.normal_timed_ns += o.normal_timed_ns;
        self.normal_timed_points += o.normal_timed_points;
        self.normal_timed_twice += o.normal_timed_twice;
        self.normal_timed_twice_ns += o.normal_timed_twice_ns;
        self.normal_timed_twice_points += o.normal_timed_twice_points;
        self.rough_hits += o.rough_hits;
        self.sun_hits += o.sun_hits;
        self.sun_samples += o.sun_samples;
        self.sun_rays += o.sun_rays;
        self.sun_occluded += o.sun_occluded;
        self.object_rays += o.object_rays;
        self.object_hits += o.object_hits;
        self.sun_object_occluded += o.sun_object_occluded;
        self.object_leaks += o.object_leaks;
    }
}

impl Counters {
    /// Estimated thread-seconds that mapped normals add to the trace: the number of normals
    /// times what one more normal adds to a timed interval. Each interval is modelled as
    /// `clock + k x normals` (k doubled where the batch is evaluated twice); the sums of the
    /// two kinds of intervals give the two unknowns, and k is the cost of a normal.
    ///
    /// An interval with one evaluation overstates its cost: reading the clock waits for the work
    /// in flight before it to finish, so the interval also holds the overlap with neighbouring
    /// work that an untimed evaluation enjoys. The second evaluation cancels that and the
    /// clock's own cost. Checked against rendering the default scene with every batch's normals
    /// evaluated twice: 0.10-0.32 s more trace (four interleaved pairs) where this reads
    /// 0.26 s. The intercept, about 200 ns an interval against the clock's 24, is left out: the
    /// second evaluation finds the texels in cache and the pipeline busy, so what a batch costs
    /// beyond its normals' marginal cost is not separable from the clock's (perf, which
    /// attributes stalls to the instructions waiting, gives the normal path 14.5 % of the
    /// trace's samples where this reads 9 %). Renders too small to have timed a pair fall back
    /// to the single intervals less [`clock_overhead_ns`].
    pub fn normal_map_thread_seconds(&self) -> f64 {
        let (n1, s1) = (self.normal_timed as f64, self.normal_timed_points as f64);
        let (n2, s2) = (
            self.normal_timed_twice as f64,
            self.normal_timed_twice_points as f64,
        );
        let (t1, t2) = (
            self.normal_timed_ns as f64,
            self.normal_timed_twice_ns as f64,
        );
        // t1 = clock n1 + k s1 and t2 = clock n2 + 2 k s2. The denominator is n1 n2 (2 m2 - m1)
        // for mean batch sizes m1, m2: solved only while the paired batches are not much
        // smaller than the single ones, where noise would swamp it.
        let denominator = 2.0 * s2 * n1 - s1 * n2;
        let per_normal_ns = if n2 > 0.0 && denominator > 0.5 * s2 * n1 {
            (t2 * n1 - t1 * n2) / denominator
        } else if s1 > 0.0 {
            (t1 - clock_overhead_ns() * n1) / s1
        } else {
            return 0.0;
        };
        per_normal_ns.max(0.0) * 1e-9 * self.normal_evals as f64
    }
}

/// What an empty timed interval reads, ns: the clock's own cost inside every interval it
/// times. Measured once per process as the median of 1001 empty intervals timed exactly as the
/// mapped normals are (about 24 ns here); only renders too small to have timed a pair of
/// evaluations use it ([`Counters::normal_map_thread_seconds`]).
pub(crate) fn clock_overhead_ns() -> f64 {
    static OVERHEAD: std::sync::OnceLock<f64> = std::sync::OnceLock::new();
    *OVERHEAD.get_or_init(|| {
        let mut v: Vec<u64> = (0..1001)
            .map(|_| {
                let t0 = std::time::Instant::now();
                t0.elapsed().as_nanos() as u64
            })
            .collect();
        v.sort_unstable();
        v[500] as f64
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_cost_is_solved_from_single_and_paired_intervals() {
        let c = Counters {
            normal_evals: 6400,
            normal_timed: 100,
            normal_timed_points: 100,
            normal_timed_ns: 12_000,
            normal_timed_twice: 100,
            normal_timed_twice_points: 100,
            normal_timed_twice_ns: 18_000,
            ..Counters::default()
        };
        // One normal an interval: 180 - 120 ns per evaluation, whatever the clock costs.
        assert!((c.normal_map_thread_seconds() - 6400.0 * 60e-9).abs() < 1e-12);
        // A second evaluation that seems free counts as free, not negative.
        let free = Counters {
            normal_timed_twice_ns: 11_000,
            ..c
        };
        assert_eq!(free.normal_map_thread_seconds(), 0.0);
        // Without pairs, or with paired batches under half the size of the single ones (too
        // noisy to solve), the single intervals less the clock's cost.
        let expected = (120.0 - clock_overhead_ns()).max(0.0) * 1e-9 * 6400.0;
        for single in [
            Counters {
                normal_timed_twice: 0,
                normal_timed_twice_ns: 0,
                normal_timed_twice_points: 0,
                ..c
            },
            Counters {
                normal_timed_twice_points: 60,
                ..c
            },
        ] {
            assert!((single.normal_map_thread_seconds() - expected).abs() < 1e-12);
        }
        assert_eq!(Counters::default().normal_map_thread_seconds(), 0.0);
        // Batches of different sizes: a 30 ns clock and 20 ns a normal, 10 normals an interval
        // alone and 14 in a pair's; the estimate recovers the 20 ns.
        let batches = Counters {
            normal_evals: 6400,
            normal_timed: 100,
            normal_timed_points: 1000,
            normal_timed_ns: 100 * 30 + 20 * 1000,
            normal_timed_twice: 50,
            normal_timed_twice_points: 700,
            normal_timed_twice_ns: 50 * 30 + 2 * 20 * 700,
            ..Counters::default()
        };
        assert!((batches.normal_map_thread_seconds() - 6400.0 * 20e-9).abs() < 1e-12);
    }
}
