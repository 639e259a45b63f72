//! The CPU ground truth: exact intersection of a tangent-space ray with the point-sampled height
//! field (a 2-D DDA over texel columns: tops and walls) and with the bilinear surface (per cell
//! between texel centres, the roots of a quadratic). Double precision throughout.
//!
//! A ray is P(z) = p0 + e * z: its parameter is its depth (spec convention, E.z = 1).

use crate::heightmap::HeightMap;
use crate::pyramid::Addressing;
use glam::DVec2;
use rayon::prelude::*;

/// Which surface the height field stands for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Surface {
    /// Each texel a flat-topped column (what point sampling sees).
    Point,
    /// Bilinear interpolation between texel centres at ((i + 0.5) / width, (j + 0.5) / height).
    Bilinear,
}

#[derive(Clone, Copy, Debug, PartialEq)]
/// A tangent-space ray P(z) = p0 + e z.
pub struct Ray {
    /// Where the ray meets the polygon (uv).
    pub p0: DVec2,
    /// uv change per unit of depth.
    pub e: DVec2,
}

impl Ray {
    /// The ray's uv at depth `z`.
    pub fn at(&self, z: f64) -> DVec2 {
        self.p0 + self.e * z
    }
}

/// Where a ray meets the surface, or `None` when it leaves a clamped (terrain) map first.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Hit uv.
    pub uv: DVec2,
    /// Hit depth.
    pub z: f64,
}

/// The exact first intersection of `ray` with `surface`, or `None` when it leaves a clamped map.
pub fn intersect(
    map: &HeightMap,
    addressing: Addressing,
    surface: Surface,
    ray: Ray,
) -> Option<Hit> {
    match surface {
        Surface::Point => intersect_point(map, addressing, ray),
        Surface::Bilinear => intersect_bilinear(map, addressing, ray),
    }
}

/// Many rays in parallel, in order.
pub fn intersect_all(
    map: &HeightMap,
    addressing: Addressing,
    surface: Surface,
    rays: &[Option<Ray>],
) -> Vec<Option<Hit>> {
    rays.par_iter()
        .map(|r| r.and_then(|r| intersect(map, addressing, surface, r)))
        .collect()
}

/// Walks the cells of the texel grid (`n` cells per unit of uv on each axis, offset by `offset`
/// texels) that the ray's footprint crosses, calling `visit(ix, iy, z_in, z_out)` until it returns
/// `Some`. Ends when the ray gets deeper than 1 (every surface point lies above).
fn walk_cells<T>(
    ray: Ray,
    n: DVec2,
    offset: f64,
    mut visit: impl FnMut(i64, i64, f64, f64) -> Option<T>,
) -> Option<T> {
    let q = ray.p0 * n - offset;
    let (mut ix, mut iy) = (q.x.floor() as i64, q.y.floor() as i64);
    let axis = |q: f64, i: i64, e: f64, n: f64| -> (f64, f64) {
        if e > 0.0 {
            ((i as f64 + 1.0 - q) / (e * n), 1.0 / (e * n))
        } else if e < 0.0 {
            ((i as f64 - q) / (e * n), -1.0 / (e * n))
        } else {
            (f64::INFINITY, f64::INFINITY)
        }
    };
    let (mut next_x, dx) = axis(q.x, ix, ray.e.x, n.x);
    let (mut next_y, dy) = axis(q.y, iy, ray.e.y, n.y);
    let (sx, sy) = (ray.e.x.signum() as i64, ray.e.y.signum() as i64);
    let mut z_in = 0.0;
    loop {
        let z_out = next_x.min(next_y);
        if let Some(found) = visit(ix, iy, z_in, z_out) {
            return Some(found);
        }
        if z_out > 1.0 {
            // Cannot happen for depths in [0,1]: `visit` hits by z = 1 at the latest.
            return None;
        }
        if next_x < next_y {
            ix += sx;
            z_in = next_x;
            next_x += dx;
        } else {
            iy += sy;
            z_in = next_y;
            next_y += dy;
        }
    }
}

/// Depth at which a clamped ray leaves [0,1]^2 (infinite for wrapped maps).
fn leave_depth(ray: Ray, addressing: Addressing) -> f64 {
    if addressing == Addressing::Wrap {
        return f64::INFINITY;
    }
    let axis = |p: f64, e: f64| {
        if e > 0.0 {
            (1.0 - p) / e
        } else if e < 0.0 {
            -p / e
        } else {
            f64::INFINITY
        }
    };
    axis(ray.p0.x, ray.e.x).min(axis(ray.p0.y, ray.e.y))
}

fn intersect_point(map: &HeightMap, addressing: Addressing, ray: Ray) -> Option<Hit> {
    let leave = leave_depth(ray, addressing);
    if addressing == Addressing::Clamp
        && (ray.p0.cmplt(DVec2::ZERO).any() || ray.p0.cmpge(DVec2::ONE).any())
    {
        return None;
    }
    walk_cells(ray, map.texels_per_uv(), 0.0, |ix, iy, z_in, z_out| {
        if z_in >= leave {
            return Some(None);
        }
        let d = f64::from(map.at(
            addressing.texel(ix, map.width),
            addressing.texel(iy, map.height),
        ));
        let z = if z_in >= d {
            z_in // the column's wall
        } else if z_out >= d {
            d // the column's top
        } else {
            return None;
        };
        Some((z < leave).then(|| Hit { uv: ray.at(z), z }))
    })
    .flatten()
}

fn intersect_bilinear(map: &HeightMap, addressing: Addressing, ray: Ray) -> Option<Hit> {
    let n = map.texels_per_uv();
    let leave = leave_depth(ray, addressing);
    if leave <= 0.0 {
        return None;
    }
    let d = |i: i64, j: i64| {
        f64::from(map.at(
            addressing.texel(i, map.width),
            addressing.texel(j, map.height),
        ))
    };
    walk_cells(ray, n, 0.5, |cx, cy, z_in, z_out| {
        if z_in >= leave {
            return Some(None);
        }
        let (s00, s10, s01, s11) = (d(cx, cy), d(cx + 1, cy), d(cx, cy + 1), d(cx + 1, cy + 1));
        // Local cell coordinates f(z) = a + b z; surface s = s00 + A fx + B fy + C fx fy.
        let (ax, bx) = (ray.p0.x * n.x - 0.5 - cx as f64, ray.e.x * n.x);
        let (ay, by) = (ray.p0.y * n.y - 0.5 - cy as f64, ray.e.y * n.y);
        let (a, b, c) = (s10 - s00, s01 - s00, s00 - s10 - s01 + s11);
        // g(z) = s(z) - z = c0 + c1 z + c2 z^2; the ray is above the surface while g > 0.
        let c0 = s00 + a * ax + b * ay + c * ax * ay;
        let c1 = a * bx + b * by + c * (ax * by + ay * bx) - 1.0;
        let c2 = c * bx * by;
        let g = |z: f64| c0 + c1 * z + c2 * z * z;
        let z = if g(z_in) <= 0.0 {
            Some(z_in)
        } else {
            first_root(c0, c1, c2, z_in, z_out.min(1.0))
        }?;
        Some((z < leave).then(|| Hit { uv: ray.at(z), z }))
    })
    .flatten()
}

/// Smallest root of c0 + c1 z + c2 z^2 in [lo, hi], given the polynomial is positive at lo.
fn first_root(c0: f64, c1: f64, c2: f64, lo: f64, hi: f64) -> Option<f64> {
    let g = |z: f64| c0 + c1 * z + c2 * z * z;
    let scale = c0.abs().max(c1.abs()).max(1.0);
    let roots: [f64; 2] = if c2.abs() <= 1e-12 * scale {
        [-c0 / c1, f64::NAN]
    } else {
        let disc = c1 * c1 - 4.0 * c2 * c0;
        if disc < 0.0 {
            [f64::NAN; 2]
        } else {
            // Numerically stable pair.
            let q = -0.5 * (c1 + c1.signum() * disc.sqrt());
            [q / c2, c0 / q]
        }
    };
    let mut best = roots
        .into_iter()
        .filter(|r| r.is_finite() && *r >= lo && *r <= hi)
        .fold(f64::INFINITY, f64::min);
    // Rounding can push a root just past the cell exit while the sign has already changed.
    if best.is_infinite() && g(hi) <= 0.0 {
        best = hi;
    }
    best.is_finite().then_some(best)
}

/// The depth of texel (i, j), wherever the ray is.
fn texel_depth(map: &HeightMap, addressing: Addressing, i: i64, j: i64) -> f64 {
    f64::from(map.at(
        addressing.texel(i, map.width),
        addressing.texel(j, map.height),
    ))
}

/// The bilinear surface's depth at `p` (between texel centres at ((i + 0.5) / width, (j + 0.5)
/// / height)).
pub fn bilinear_depth(map: &HeightMap, addressing: Addressing, p: DVec2) -> f64 {
    let q = p * map.texels_per_uv() - 0.5;
    let (i, j) = (q.x.floor() as i64, q.y.floor() as i64);
    let (fx, fy) = (q.x - i as f64, q.y - j as f64);
    let d = |a: i64, b: i64| texel_depth(map, addressing, a, b);
    let top = d(i, j) * (1.0 - fx) + d(i + 1, j) * fx;
    let bottom = d(i, j + 1) * (1.0 - fx) + d(i + 1, j + 1) * fx;
    top * (1.0 - fy) + bottom * fy
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::heightmap::random_map;
    use std::path::Path;

    fn random_rays(count: usize, seed: u64) -> Vec<Ray> {
        let mut s = seed;
        let mut next = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..count)
            .map(|_| {
                let angle = next() * std::f64::consts::TAU;
                let len = next() * 2.5;
                Ray {
                    p0: DVec2::new(next(), next()),
                    e: DVec2::new(angle.cos(), angle.sin()) * len,
                }
            })
            .collect()
    }

    /// First depth where the ray is at or below `surface`, by steps of `dz`.
    fn march(ray: Ray, dz: f64, surface: impl Fn(DVec2) -> f64) -> f64 {
        let mut z = 0.0;
        while z < surface(ray.at(z)) {
            z += dz;
        }
        z
    }

    fn point_depth(map: &HeightMap, addressing: Addressing, p: DVec2) -> f64 {
        let q = p * map.texels_per_uv();
        texel_depth(map, addressing, q.x.floor() as i64, q.y.floor() as i64)
    }

    /// Square, odd, one-texel-wide and one-texel-high maps.
    const SIZES: [(u32, u32); 5] = [(16, 16), (3, 5), (1, 9), (13, 1), (12, 7)];

    #[test]
    fn point_sampled_dda_matches_fine_marching() {
        for (w, h) in SIZES {
            for sharp in [false, true] {
                let map = random_map(w, h, 7, if sharp { 4 } else { 0 });
                matches_marching(&map, 11, Surface::Point, point_depth);
            }
        }
    }

    /// `intersect` on `surface` against fine marching of `depth` along 400 random rays, wrapped
    /// and clamped (where a ray that leaves the map before the marched hit misses).
    fn matches_marching(
        map: &HeightMap,
        seed: u64,
        surface: Surface,
        depth: impl Fn(&HeightMap, Addressing, DVec2) -> f64,
    ) {
        let size = format!("{}x{}", map.width, map.height);
        for addressing in [Addressing::Wrap, Addressing::Clamp] {
            for ray in random_rays(400, seed) {
                let dz = 2e-5;
                let expected = march(ray, dz, |p| depth(map, addressing, p));
                let hit = intersect(map, addressing, surface, ray);
                let leave = leave_depth(ray, addressing);
                if (expected - leave).abs() <= dz * 1.01 {
                    continue; // marching cannot tell which comes first
                }
                match hit {
                    Some(hit) => assert!(
                        expected < leave && (hit.z - expected).abs() <= dz * 1.01,
                        "{size} {addressing:?} ray {ray:?}: {surface:?} {} march {expected}",
                        hit.z
                    ),
                    None => assert!(
                        expected > leave,
                        "{size} {addressing:?} ray {ray:?}: {surface:?} missed, march {expected}"
                    ),
                }
            }
        }
    }

    #[test]
    fn bilinear_roots_match_fine_marching() {
        for (w, h) in SIZES {
            let map = random_map(w, h, 3, 0);
            matches_marching(&map, 5, Surface::Bilinear, bilinear_depth);
        }
    }

    #[test]
    fn clamped_rays_that_leave_the_map_miss() {
        let map = HeightMap::from_depths(Path::new("deep"), 4, 4, vec![1.0; 16]).unwrap();
        let leaving = Ray {
            p0: DVec2::new(0.9, 0.5),
            e: DVec2::new(2.0, 0.0),
        };
        for surface in [Surface::Point, Surface::Bilinear] {
            assert_eq!(intersect(&map, Addressing::Clamp, surface, leaving), None);
            let hit = intersect(&map, Addressing::Wrap, surface, leaving).unwrap();
            assert!((hit.z - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn a_vertical_ray_stops_on_the_top_of_its_column() {
        let map = random_map(8, 8, 1, 4);
        let ray = Ray {
            p0: DVec2::new(0.3, 0.6),
            e: DVec2::ZERO,
        };
        let hit = intersect(&map, Addressing::Wrap, Surface::Point, ray).unwrap();
        assert_eq!(hit.z, f64::from(map.at(2, 4)));
    }
}
