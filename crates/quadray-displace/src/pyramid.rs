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

/// All levels, finest first: `levels[k]` is (2^(n-k))^2 depths.
#[derive(Clone, Debug, PartialEq)]
pub struct Pyramid {
    /// `levels[k]` holds (2^(n-k))^2 depths, row-major.
    pub levels: Vec<Vec<f32>>,
}

impl Pyramid {
    /// The paper's pyramid: a safe bound for the point-sampled field.
    pub fn build(map: &HeightMap) -> Self {
        Self::from_level0(map.depth.clone(), map.size())
    }

    /// The conservative pyramid for the bilinear surface (spec pitfall): level 0 holds the minimum
    /// over each texel's 3x3 neighbourhood, every texel centre that bilinear interpolation inside
    /// the texel can reach.
    pub fn build_conservative(map: &HeightMap, addressing: Addressing) -> Self {
        let n = map.size();
        let mut level0 = Vec::with_capacity(map.depth.len());
        for j in 0..n as i64 {
            for i in 0..n as i64 {
                let mut m = f32::MAX;
                for dj in -1..=1 {
                    for di in -1..=1 {
                        m = m.min(map.at(addressing.texel(i + di, n), addressing.texel(j + dj, n)));
                    }
                }
                level0.push(m);
            }
        }
        Self::from_level0(level0, n)
    }

    fn from_level0(level0: Vec<f32>, size: u32) -> Self {
        let mut levels = vec![level0];
        let mut n = size as usize;
        while n > 1 {
            let prev = levels.last().expect("level 0");
            let half = n / 2;
            let next = (0..half * half)
                .map(|k| {
                    let (i, j) = (2 * (k % half), 2 * (k / half));
                    prev[j * n + i]
                        .min(prev[j * n + i + 1])
                        .min(prev[(j + 1) * n + i])
                        .min(prev[(j + 1) * n + i + 1])
                })
                .collect();
            levels.push(next);
            n = half;
        }
        Self { levels }
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

    #[test]
    fn every_node_is_the_minimum_of_its_leaves() {
        let depth: Vec<f32> = (0..64).map(|i| ((i * 37) % 64) as f32 / 64.0).collect();
        let map = HeightMap::from_depths(Path::new("t"), 8, depth).unwrap();
        let p = Pyramid::build(&map);
        assert_eq!(p.levels.len(), 4);
        assert_eq!(p.levels[3], vec![0.0]);
        for (k, level) in p.levels.iter().enumerate() {
            let side = 8 >> k;
            for j in 0..side {
                for i in 0..side {
                    let leaves = (0..1 << k).flat_map(|dy| (0..1 << k).map(move |dx| (dx, dy)));
                    let m = leaves
                        .map(|(dx, dy)| map.at((i << k) + dx, (j << k) + dy))
                        .fold(f32::MAX, f32::min);
                    assert_eq!(level[(j * side + i) as usize], m);
                }
            }
        }
    }

    #[test]
    fn conservative_level0_bounds_the_neighbourhood_with_wrap() {
        let mut depth = vec![1.0; 16];
        depth[0] = 0.25; // corner texel: its wrapped neighbours include the opposite corner
        let map = HeightMap::from_depths(Path::new("t"), 4, depth).unwrap();
        let wrap = Pyramid::build_conservative(&map, Addressing::Wrap);
        assert_eq!(wrap.levels[0][15], 0.25);
        let clamp = Pyramid::build_conservative(&map, Addressing::Clamp);
        assert_eq!(clamp.levels[0][15], 1.0);
        assert_eq!(clamp.levels[0][5], 0.25);
    }
}
