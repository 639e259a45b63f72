//! The texels each GPU search reads, recounted on the CPU: the shader's searches run again here,
//! in single precision as the shader runs them, on the CPU's own rays
//! ([`crate::primary_rays`]), counting every texel read. The shader's own counter must agree
//! with this count; an extra read, a skipped level or a search that stops late shows up as a
//! difference.

use crate::Settings;
use crate::heightmap::HeightMap;
use crate::method::Method;
use crate::pyramid::{Addressing, Pyramid};
use crate::reference::Ray;
use glam::Vec2;

/// The level a pyramid trace starts on.
#[derive(Clone, Copy)]
enum Start {
    /// No coarser than the ray's footprint needs (the shader's choice).
    Footprint,
    /// The root (the paper's), which the shader no longer does: for the comparison.
    #[cfg(test)]
    Root,
}

/// The texels one hand-bilinear depth sample reads.
const BILINEAR_READS: u32 = 4;

/// What a search reads from: the map and its point-sampled pyramid.
pub struct SearchInput<'a> {
    /// The height map (the bilinear samples').
    pub map: &'a HeightMap,
    /// Its point-sampled pyramid ([`Pyramid::build`]).
    pub pyramid: &'a Pyramid,
    /// How reads outside the map behave.
    pub addressing: Addressing,
}

impl SearchInput<'_> {
    /// Texels `s.method`'s search reads for `ray` at the finest level (`Lod::Level(0)`), or
    /// None for the searches not recounted here (cone stepping, the bilinear pyramid, the
    /// mesh).
    pub fn texel_reads(&self, s: &Settings, ray: Ray) -> Option<u32> {
        let (p0, e) = (ray.p0.as_vec2(), ray.e.as_vec2());
        match s.method {
            Method::Pyramid => Some(self.pyramid_reads(p0, e, false, Start::Footprint)),
            Method::PyramidAscend => Some(self.pyramid_reads(p0, e, true, Start::Footprint)),
            Method::Pom => Some(self.linear_search_reads(s, p0, e)),
            Method::Relief => {
                Some(self.linear_search_reads(s, p0, e) + BILINEAR_READS * s.binary_steps)
            }
            Method::Parallax => Some(BILINEAR_READS),
            Method::Bump => Some(0),
            Method::PyramidBilinear | Method::Cone | Method::Mesh => None,
        }
    }

    /// `pyramid_trace` from `start` down to level 0: one read per node visited.
    fn pyramid_reads(&self, p0: Vec2, e: Vec2, ascend: bool, start: Start) -> u32 {
        let pyramid = self.pyramid;
        let clamp = self.addressing == Addressing::Clamp;
        let top = pyramid.levels.len() as i32 - 1;
        let size = Vec2::new(pyramid.width as f32, pyramid.height as f32);
        let (x0, ex) = (p0 * size, e * size);
        let footprint = ex.length();
        let delta = 0.001f32;
        let needed = footprint.max(1.0).log2().ceil() as i32 - 1;
        let mut level = match start {
            Start::Footprint => top.min(needed.max(0)),
            #[cfg(test)]
            Start::Root => top,
        };
        let (mut z, mut reads) = (0.0f32, 0u32);
        while level >= 0 {
            let p = p0 + e * z;
            if clamp && (p.x < 0.0 || p.y < 0.0 || p.x >= 1.0 || p.y >= 1.0) {
                break;
            }
            let x = x0 + ex * z;
            let mut copy = (x / size).floor();
            copy -= Vec2::select(x.cmplt(copy * size), Vec2::ONE, Vec2::ZERO);
            if clamp {
                copy = Vec2::ZERO;
            }
            let origin = copy * size;
            let scale = (1u32 << level) as f32;
            let node = ((x - origin) / scale)
                .floor()
                .clamp(Vec2::ZERO, (size / scale).ceil() - 1.0);
            let (width, _) = pyramid.level_size(level as u32);
            let d =
                pyramid.levels[level as usize][node.y as usize * width as usize + node.x as usize];
            reads += 1;
            let lo = origin + node * scale;
            let hi = origin + (node * scale + scale).min(size);
            if z < d {
                let advanced = x0 + ex * d;
                if advanced.cmpge(lo).all() && advanced.cmplt(hi).all() {
                    z = d;
                    level -= 1;
                } else {
                    let boundary = Vec2::select(ex.cmpgt(Vec2::ZERO), hi, lo);
                    let to =
                        |b: f32, x0: f32, ex: f32| if ex != 0.0 { (b - x0) / ex } else { 1.0e30 };
                    let to_boundary =
                        Vec2::new(to(boundary.x, x0.x, ex.x), to(boundary.y, x0.y, ex.y));
                    let crossing = if to_boundary.x < to_boundary.y {
                        to_boundary.x
                    } else {
                        to_boundary.y
                    };
                    z = (z.max(crossing) + delta / footprint).max(f32::from_bits(z.to_bits() + 1));
                    if ascend {
                        level = (level + 1).min(top);
                    }
                }
            } else {
                level -= 1;
            }
        }
        reads
    }

    /// The linear search POM and relief mapping share: a sample at the polygon, then one a
    /// layer deeper until the ray is at or below the surface.
    fn linear_search_reads(&self, s: &Settings, p0: Vec2, e: Vec2) -> u32 {
        // The view direction's tangent-space z, from the ray's slope.
        let view_z = 1.0 / (1.0 + (e / s.depth_scale).length_squared()).sqrt();
        let (min, max) = (s.layers.min as f32, s.layers.max as f32);
        // WGSL's round() takes ties to even.
        let layers = (max + (min - max) * view_z).round_ties_even().max(1.0);
        let dz = 1.0 / layers;
        let mut z_below = 0.0f32;
        let mut d = self.depth_bilinear(p0);
        let (mut steps, mut reads) = (0u32, BILINEAR_READS);
        while z_below < d && (steps as f32) < layers + 2.0 {
            z_below += dz;
            d = self.depth_bilinear(p0 + e * z_below);
            steps += 1;
            reads += BILINEAR_READS;
        }
        reads
    }

    /// The bilinear depth between texel centres, as `depth_bilinear` in `trace.wgsl`.
    fn depth_bilinear(&self, p: Vec2) -> f32 {
        let map = self.map;
        let x = p * Vec2::new(map.width as f32, map.height as f32) - 0.5;
        let (i, f) = (x.floor(), x - x.floor());
        let at = |di: i64, dj: i64| {
            map.at(
                self.addressing.texel(i.x as i64 + di, map.width),
                self.addressing.texel(i.y as i64 + dj, map.height),
            )
        };
        let mix = |a: f32, b: f32, t: f32| a + (b - a) * t;
        mix(
            mix(at(0, 0), at(1, 0), f.x),
            mix(at(0, 1), at(1, 1), f.x),
            f.y,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::maps::BUNDLED;

    /// Starting where the ray's footprint needs rather than at the root reads fewer texels for
    /// the same trace (the GPU's hits are the same from any level: `gpu_vs_reference.rs`): on the
    /// tile map at 30, 60 and 80 degrees over a grid of rays: measured 32,171, 52,809 and 88,018
    /// reads against 52,563, 64,985 and 92,114 from the root (on the GPU at 60 degrees, 64x64:
    /// 50,605 against 61,642).
    #[test]
    fn the_footprint_start_reads_fewer_texels_than_the_root() {
        let map = BUNDLED[0].load().unwrap();
        let pyramid = Pyramid::build(&map);
        let input = SearchInput {
            map: &map,
            pyramid: &pyramid,
            addressing: Addressing::Wrap,
        };
        for angle in [30.0f32, 60.0, 80.0] {
            // A view ray at `angle` from the normal, depth scale 0.1: uv per unit of depth.
            let e = Vec2::new(0.6, 0.8) * angle.to_radians().tan() * 0.1;
            let (mut footprint, mut root) = (0u64, 0u64);
            for i in 0..64 {
                for j in 0..64 {
                    let p0 = Vec2::new(i as f32 + 0.37, j as f32 + 0.61) / 64.0;
                    footprint += u64::from(input.pyramid_reads(p0, e, false, Start::Footprint));
                    root += u64::from(input.pyramid_reads(p0, e, false, Start::Root));
                }
            }
            println!(
                "{angle} deg: {footprint} reads from the footprint's level, {root} from the root"
            );
            assert!(
                footprint < root,
                "{angle} deg: {footprint} vs {root} from the root"
            );
        }
    }
}
