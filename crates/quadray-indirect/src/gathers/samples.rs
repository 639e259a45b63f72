//! The baselines the quadtree is measured against, both gather passes of [`crate::Gather`]
//! (`brute_force.rs`, `rsm_sampling.rs`): the brute force over every VPL
//! (the GPU reference), and RSM sampling (Dachsbacher & Stamminger 2005) whose sample pattern is
//! made here.

/// The seed of the RSM-sampling pattern the gather uses.
pub const SAMPLE_SEED: u64 = 0x5eed;

use quadray_core::random::SplitMix;

/// `n` points in the unit square, no two closer than a radius that starts at 0.75 / sqrt(n) and
/// shrinks when dart throwing stalls (a Poisson-disk pattern).
pub fn poisson_disk(n: u32, seed: u64) -> Vec<[f32; 2]> {
    let mut rng = SplitMix(seed);
    let mut radius = 0.75 / (n.max(1) as f32).sqrt();
    let mut points: Vec<[f32; 2]> = Vec::with_capacity(n as usize);
    let mut misses = 0;
    while points.len() < n as usize {
        let p = [rng.next_f32(), rng.next_f32()];
        let free = points
            .iter()
            .all(|q| (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) >= radius * radius);
        if free {
            points.push(p);
            misses = 0;
        } else {
            misses += 1;
            if misses > 200 {
                radius *= 0.9;
                misses = 0;
            }
        }
    }
    points
}

/// RSM sampling pattern: sample i at offset xi1 * R * (sin 2 pi xi2, cos 2 pi xi2) texels from the
/// pixel's projection (dense near it, sparse far away, as in the RSM paper) with weight
/// 2 pi xi1 R^2 / n, the inverse of that density, so the sum estimates the sum over every texel
/// within R. Returns (dx, dy, weight, R); the shader shrinks the disk (and the weights with its
/// area) where the RSM's farthest corner is nearer than R.
pub fn rsm_samples(n: u32, radius_texels: f32, seed: u64) -> Vec<[f32; 4]> {
    poisson_disk(n, seed)
        .into_iter()
        .map(|[xi1, xi2]| {
            let angle = std::f32::consts::TAU * xi2;
            let r = xi1 * radius_texels;
            let weight = std::f32::consts::TAU * xi1 * radius_texels * radius_texels / n as f32;
            [r * angle.sin(), r * angle.cos(), weight, radius_texels]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn poisson_points_are_spread_and_inside() {
        let pts = poisson_disk(256, 7);
        assert_eq!(pts.len(), 256);
        let mut closest = f32::MAX;
        for (i, p) in pts.iter().enumerate() {
            assert!((0.0..1.0).contains(&p[0]) && (0.0..1.0).contains(&p[1]));
            for q in &pts[i + 1..] {
                closest = closest.min(((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt());
            }
        }
        // white noise of 256 points has closest pairs far below 0.02
        assert!(closest > 0.02, "closest pair {closest}");
    }

    #[test]
    fn weights_integrate_the_disk() {
        // the weights of a uniform-in-(xi1, xi2) pattern sum to the disk's area
        let r = 10.0;
        let total: f32 = rsm_samples(2040, r, 1).iter().map(|s| s[2]).sum();
        let area = std::f32::consts::PI * r * r;
        assert!((total / area - 1.0).abs() < 0.02, "{total} vs {area}");
    }
}
