//! The max-height (min-depth) image pyramid of section 3.1: level k+1 texel (i,j) holds the
//! minimum depth of level-k texels (2i..2i+1, 2j..2j+1); the root (level n) is 1x1.

use crate::heightmap::HeightMap;

/// How texel reads outside [0, size) behave: a tiled surface wraps, a terrain patch clamps (and
/// its rays stop when they leave the map).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Addressing {
    /// Reads wrap around (a tiled surface).
    Wrap,
    /// Reads clamp to the edge (a terrain patch).
    Clamp,
}

impl Addressing {
    /// Texel index `i` of a `size`-texel row under this addressing.
    pub fn texel(self, i: i64, size: u32) -> u32 {
        match self {
            Addressing::Wrap => i.rem_euclid(size as i64) as u32,
            Addressing::Clamp => i.clamp(0, size as i64 - 1) as u32,
        }
    }
}

/// Width and height of level `k` of the pyramid of a `width` x `height` map: `max(padded >> k, 1)`
/// on each axis, the padded size being the map's rounded up to powers of two.
pub fn level_size(width: u32, height: u32, k: u32) -> (u32, u32) {
    let side = |n: u32| (n.next_power_of_two() >> k).max(1);
    (side(width), side(height))
}

/// All levels, finest first, over the map padded to powers of two (padding texels at depth 1,
/// the deepest, so a node's minimum is that of the map texels it covers): level k is
/// [`Pyramid::level_size`], a wgpu mip chain.
#[derive(Clone, Debug, PartialEq)]
pub struct Pyramid {
    /// The map's width in texels (level 0 pads it to the next power of two).
    pub width: u32,
    /// The map's height in texels (level 0 pads it to the next power of two).
    pub height: u32,
    /// `levels[k]` holds `level_size(k)` depths, row-major.
    pub levels: Vec<Vec<f32>>,
}

impl Pyramid {
    /// The paper's pyramid: a safe bound for the point-sampled field.
    pub fn build(map: &HeightMap) -> Self {
        Self::from_level0(map, |i, j| map.at(i, j))
    }

    /// The conservative pyramid for the bilinear surface (spec pitfall): level 0 holds the minimum
    /// over each texel's 3x3 neighbourhood, every texel centre that bilinear interpolation inside
    /// the texel can reach.
    pub fn build_conservative(map: &HeightMap, addressing: Addressing) -> Self {
        let (w, h) = (map.width, map.height);
        Self::from_level0(map, |i, j| {
            let mut m = f32::MAX;
            for dj in -1..=1 {
                for di in -1..=1 {
                    let x = addressing.texel(i64::from(i) + di, w);
                    let y = addressing.texel(i64::from(j) + dj, h);
                    m = m.min(map.at(x, y));
                }
            }
            m
        })
    }

    /// Level 0 padded to powers of two (`texel` gives the map's texels, 1 fills the rest), then
    /// every level above.
    fn from_level0(map: &HeightMap, texel: impl Fn(u32, u32) -> f32) -> Self {
        let (padded_w, padded_h) = map.padded_size();
        let level0 = (0..padded_h)
            .flat_map(|j| (0..padded_w).map(move |i| (i, j)))
            .map(|(i, j)| {
                if i < map.width && j < map.height {
                    texel(i, j)
                } else {
                    1.0
                }
            })
            .collect();
        let mut pyramid = Self {
            width: map.width,
            height: map.height,
            levels: vec![level0],
        };
        for k in 1..=map.levels() {
            let (w, h) = pyramid.level_size(k - 1);
            let (half_w, half_h) = pyramid.level_size(k);
            let prev = &pyramid.levels[k as usize - 1];
            // A side already down to 1 texel has only one child per parent on that axis.
            let at = |i: u32, j: u32| prev[(j.min(h - 1) * w + i.min(w - 1)) as usize];
            let next = (0..half_h)
                .flat_map(|j| (0..half_w).map(move |i| (2 * i, 2 * j)))
                .map(|(i, j)| {
                    at(i, j)
                        .min(at(i + 1, j))
                        .min(at(i, j + 1))
                        .min(at(i + 1, j + 1))
                })
                .collect();
            pyramid.levels.push(next);
        }
        pyramid
    }

    /// Width and height of level `k`.
    pub fn level_size(&self, k: u32) -> (u32, u32) {
        level_size(self.width, self.height, k)
    }

    /// Bytes of all levels beyond level 0 (the extra memory the method costs, as f32).
    pub fn extra_bytes(&self) -> usize {
        self.levels[1..].iter().map(|l| l.len() * 4).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// A `width` x `height` map of scattered depths in (0, 1).
    fn scattered(width: u32, height: u32) -> HeightMap {
        let depth = (0..width * height)
            .map(|i| ((i * 37) % 61 + 1) as f32 / 64.0)
            .collect();
        HeightMap::from_depths(Path::new("t"), width, height, depth).unwrap()
    }

    #[test]
    fn every_node_is_the_minimum_of_the_map_texels_it_covers() {
        for (w, h) in [(8, 8), (3, 5), (1, 7), (6, 1), (1, 1), (13, 4)] {
            let map = scattered(w, h);
            let p = Pyramid::build(&map);
            assert_eq!(p.levels.len() as u32, map.levels() + 1, "{w}x{h}");
            assert_eq!(p.level_size(map.levels()), (1, 1), "{w}x{h}");
            for (k, level) in p.levels.iter().enumerate() {
                let (lw, lh) = p.level_size(k as u32);
                assert_eq!(level.len() as u32, lw * lh, "{w}x{h} level {k}");
                for j in 0..lh {
                    for i in 0..lw {
                        // The map texels under node (i, j); none (depth 1) for a padding node.
                        let xs = (i << k)..((i + 1) << k).min(w);
                        let ys = (j << k)..((j + 1) << k).min(h);
                        let m = ys
                            .flat_map(|y| xs.clone().map(move |x| (x, y)))
                            .map(|(x, y)| map.at(x, y))
                            .fold(1.0, f32::min);
                        assert_eq!(level[(j * lw + i) as usize], m, "{w}x{h} level {k}");
                    }
                }
            }
        }
    }

    #[test]
    fn a_rectangular_map_pads_each_side_on_its_own() {
        let p = Pyramid::build(&scattered(4096, 16));
        assert_eq!(p.level_size(0), (4096, 16));
        assert_eq!(p.levels[0].len(), 4096 * 16);
        assert_eq!(p.level_size(5), (128, 1));
        assert_eq!(p.level_size(12), (1, 1));
    }

    #[test]
    fn conservative_level0_bounds_the_neighbourhood_with_wrap() {
        let mut depth = vec![1.0; 16];
        depth[0] = 0.25; // corner texel: its wrapped neighbours include the opposite corner
        let map = HeightMap::from_depths(Path::new("t"), 4, 4, depth).unwrap();
        let wrap = Pyramid::build_conservative(&map, Addressing::Wrap);
        assert_eq!(wrap.levels[0][15], 0.25);
        let clamp = Pyramid::build_conservative(&map, Addressing::Clamp);
        assert_eq!(clamp.levels[0][15], 1.0);
        assert_eq!(clamp.levels[0][5], 0.25);
    }

    #[test]
    fn conservative_neighbours_wrap_at_the_real_size_not_the_padded_one() {
        let mut depth = vec![1.0; 3 * 5];
        depth[2] = 0.25; // texel (2, 0): with wrap, a neighbour of (0, 4) across both edges
        let map = HeightMap::from_depths(Path::new("t"), 3, 5, depth).unwrap();
        let wrap = Pyramid::build_conservative(&map, Addressing::Wrap);
        assert_eq!(wrap.level_size(0), (4, 8));
        assert_eq!(wrap.levels[0][4 * 4], 0.25);
        // Padding texels stay deepest.
        assert_eq!(wrap.levels[0][3], 1.0);
        assert_eq!(wrap.levels[0][4 * 5], 1.0);
        let clamp = Pyramid::build_conservative(&map, Addressing::Clamp);
        assert_eq!(clamp.levels[0][4 * 4], 1.0);
    }
}
