//! Meshes with a [`PyramidMaterial`](crate::PyramidMaterial) in the indirect light's scene: their
//! displaced surface as triangles, with the material's albedo. Each of the mesh's triangles is
//! cut into a grid of k x k smaller ones whose corners lie on the bilinear height field at their
//! uv (`quadray_displace::reference::bilinear_depth`), sunk along the polygon's normal by the
//! material's depth as its trace sinks them, and carry the height field's normal as the
//! material's G-buffer writes it (central differences one texel apart). k gives about one corner
//! a texel, capped so that a mesh adds at most [`DISPLACED_TRIANGLES_MAX`] triangles.
//!
//! Why corners on the bilinear surface rather than the point-sampled columns the material traces:
//! at the same budget they land nearer the traced surface as a light sees it
//! (`tests/gi_displaced.rs`, figures in docs/displacement.md).

use bevy::math::{Affine2, Vec3A};
use bevy::mesh::{PrimitiveTopology, VertexAttributeValues};
use bevy::prelude::*;
use quadray_displace::heightmap::HeightMap;
use quadray_displace::pyramid::Addressing;
use quadray_displace::reference::bilinear_depth;
use quadray_indirect::scene::Vertex;

/// The most triangles one displaced mesh adds to the indirect light's scene (its RSM and its
/// occupancy grid): a mesh's triangles are cut into k x k each, k the texels (of the depth map,
/// or of the colour texture where finer) along a triangle's longest side, at most
/// `sqrt(DISPLACED_TRIANGLES_MAX / triangles)`. A plane's two triangles become at most a
/// 128 x 128 grid, however large the map.
pub const DISPLACED_TRIANGLES_MAX: usize = 1 << 15;

/// The height field a mesh is displaced by, as its material traces it.
pub(super) struct Displacement<'a> {
    pub map: &'a HeightMap,
    /// uv units per unit of depth (the material's `depth_scale`).
    pub depth_scale: f32,
    pub addressing: Addressing,
}

/// The diffuse albedo a mesh's material gives the RSM at a uv: the base colour times its texture
/// (read on the CPU), times 1 - metallic.
pub(super) struct Albedo<'a> {
    pub base: Vec3,
    pub texture: Option<&'a ColourMap>,
    pub uv_transform: Affine2,
}

impl Albedo<'_> {
    fn at(&self, uv: Vec2) -> [f32; 3] {
        let tint = self
            .texture
            .map_or(Vec3::ONE, |t| t.at(self.uv_transform.transform_point2(uv)));
        (self.base * tint).to_array()
    }
}

/// A colour texture as the RSM reads it: linear RGB, averaged down to at most
/// [`ColourMap::SIDE`] texels a side (the grid's corners are that sparse), wrapping or clamped
/// as the image's sampler addresses it.
pub(super) struct ColourMap {
    width: u32,
    height: u32,
    texels: Vec<Vec3>,
    wrap: [bool; 2],
}

impl ColourMap {
    /// The most texels a side kept: each block of the image averaged into one.
    pub const SIDE: u32 = 256;

    /// The image's colours, or `None` when it has no CPU-side data or a format that Bevy's
    /// `Image::get_color_at` does not read (block-compressed, e.g.).
    pub fn of_image(image: &Image) -> Option<Self> {
        let (w, h) = (image.width(), image.height());
        if w == 0 || h == 0 || image.data.is_none() || image.get_color_at(0, 0).is_err() {
            return None;
        }
        let block = w.max(h).div_ceil(Self::SIDE);
        let (width, height) = (w.div_ceil(block), h.div_ceil(block));
        let mut texels = Vec::with_capacity((width * height) as usize);
        for by in 0..height {
            for bx in 0..width {
                let (mut sum, mut n) = (Vec3::ZERO, 0.0);
                for y in by * block..((by + 1) * block).min(h) {
                    for x in bx * block..((bx + 1) * block).min(w) {
                        let c = LinearRgba::from(image.get_color_at(x, y).ok()?);
                        sum += Vec3::new(c.red, c.green, c.blue);
                        n += 1.0;
                    }
                }
                texels.push(sum / n);
            }
        }
        let wrap = match &image.sampler {
            bevy::image::ImageSampler::Descriptor(d) => [d.address_mode_u, d.address_mode_v]
                .map(|m| m != bevy::image::ImageAddressMode::ClampToEdge),
            // (the image plugin's default sampler clamps)
            bevy::image::ImageSampler::Default => [false; 2],
        };
        Some(Self {
            width,
            height,
            texels,
            wrap,
        })
    }

    /// Bilinear between texel centres, as a linear sampler reads it.
    fn at(&self, uv: Vec2) -> Vec3 {
        let size = Vec2::new(self.width as f32, self.height as f32);
        let x = uv * size - 0.5;
        let (i, f) = (x.floor(), x - x.floor());
        let address = |t: f32, n: u32, wrap: bool| {
            let t = t as i64;
            if wrap {
                t.rem_euclid(i64::from(n)) as usize
            } else {
                t.clamp(0, i64::from(n) - 1) as usize
            }
        };
        let texel = |dx: f32, dy: f32| {
            let (tx, ty) = (
                address(i.x + dx, self.width, self.wrap[0]),
                address(i.y + dy, self.height, self.wrap[1]),
            );
            self.texels[ty * self.width as usize + tx]
        };
        let top = texel(0.0, 0.0).lerp(texel(1.0, 0.0), f.x);
        let bottom = texel(0.0, 1.0).lerp(texel(1.0, 1.0), f.x);
        top.lerp(bottom, f.y)
    }
}

/// Appends `mesh`'s displaced surface in world space; false (nothing appended) where the mesh
/// is not a triangle list with positions and uvs.
pub(super) fn append_displaced(
    mesh: &Mesh,
    transform: &GlobalTransform,
    displacement: &Displacement,
    albedo: &Albedo,
    out: &mut Vec<[Vertex; 3]>,
) -> bool {
    if mesh.primitive_topology() != PrimitiveTopology::TriangleList {
        return false;
    }
    let (
        Some(VertexAttributeValues::Float32x3(positions)),
        Some(VertexAttributeValues::Float32x2(uvs)),
    ) = (
        mesh.attribute(Mesh::ATTRIBUTE_POSITION),
        mesh.attribute(Mesh::ATTRIBUTE_UV_0),
    )
    else {
        return false;
    };
    if uvs.len() != positions.len() {
        return false;
    }
    let normals = match mesh.attribute(Mesh::ATTRIBUTE_NORMAL) {
        Some(VertexAttributeValues::Float32x3(n)) if n.len() == positions.len() => Some(n),
        _ => None,
    };
    let corners: Vec<usize> = match mesh.indices() {
        Some(indices) => indices.iter().collect(),
        None => (0..positions.len()).collect(),
    };
    let triangles: Vec<[usize; 3]> = corners
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .filter(|t| t.iter().all(|&i| i < positions.len()))
        .collect();
    let map = displacement.map;
    let texels = Vec2::new(map.width as f32, map.height as f32);
    // about one grid corner a texel (of the map, or of the colour texture where that is finer)
    // along every side, within the budget
    let finest = albedo.texture.map_or(texels, |t| {
        texels.max(Vec2::new(t.width as f32, t.height as f32))
    });
    let longest = triangles
        .iter()
        .flat_map(|t| {
            (0..3).map(|e| {
                let d = (Vec2::from(uvs[t[(e + 1) % 3]]) - Vec2::from(uvs[t[e]])).abs() * finest;
                d.max_element()
            })
        })
        .fold(1.0f32, f32::max);
    let budget = (DISPLACED_TRIANGLES_MAX / triangles.len().max(1)).max(1);
    let k = (longest.ceil() as usize).clamp(1, budget.isqrt().max(1));
    out.reserve(triangles.len() * k * k);

    let affine = transform.affine();
    let normal_matrix = Mat3::from(affine.matrix3).inverse().transpose();
    let texel = Vec2::ONE / texels;
    let depth = |uv: Vec2| bilinear_depth(map, displacement.addressing, uv.as_dvec2()) as f32;
    let scale = displacement.depth_scale;
    let mut grid: Vec<Vertex> = Vec::with_capacity((k + 1) * (k + 2) / 2);
    // corner (i, j) of a triangle's grid is grid[row_start[i] + j]: row i holds k + 1 - i
    let row_start: Vec<usize> = (0..=k)
        .map(|i| i * (k + 1) - i * (i.max(1) - 1) / 2)
        .collect();
    for t in &triangles {
        let p = t.map(|i| Vec3::from(affine.transform_point3a(Vec3A::from(positions[i]))));
        let uv = t.map(|i| Vec2::from(uvs[i]));
        let face = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        let n = t.map(|i| {
            normals.map_or(face, |n| {
                (normal_matrix * Vec3::from(n[i])).normalize_or_zero()
            })
        });
        // world change per unit of u and of v across the triangle
        let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
        let (d1, d2) = (uv[1] - uv[0], uv[2] - uv[0]);
        let det = d1.x * d2.y - d2.x * d1.y;
        let (along_u, along_v) = if det.abs() > f32::EPSILON {
            ((e1 * d2.y - e2 * d1.y) / det, (e2 * d1.x - e1 * d2.x) / det)
        } else {
            (Vec3::ZERO, Vec3::ZERO)
        };
        // world units a uv unit (the material's world_per_uv, exact where uv is a similarity);
        // 0 on a triangle without a uv area: it stays flat
        let world_per_uv = along_u.cross(along_v).length().sqrt();
        let (tangent, bitangent) = (along_u.normalize_or_zero(), along_v.normalize_or_zero());
        grid.clear();
        for i in 0..=k {
            for j in 0..=k - i {
                let (b, c) = (i as f32 / k as f32, j as f32 / k as f32);
                let a = 1.0 - b - c;
                let at_uv = uv[0] * a + uv[1] * b + uv[2] * c;
                let polygon = p[0] * a + p[1] * b + p[2] * c;
                let normal = (n[0] * a + n[1] * b + n[2] * c).normalize_or(face);
                let sunk = world_per_uv * scale * depth(at_uv);
                // the height field's normal as the material computes it (its
                // height_field_normal), in the triangle's frame
                let du =
                    depth(at_uv + Vec2::new(texel.x, 0.0)) - depth(at_uv - Vec2::new(texel.x, 0.0));
                let dv =
                    depth(at_uv + Vec2::new(0.0, texel.y)) - depth(at_uv - Vec2::new(0.0, texel.y));
                let slope = Vec2::new(du / (2.0 * texel.x), dv / (2.0 * texel.y)) * scale;
                let tilted =
                    (slope.x * tangent + slope.y * bitangent + normal).normalize_or(normal);
                grid.push(Vertex::untextured(
                    (polygon - normal * sunk).into(),
                    tilted.into(),
                    albedo.at(at_uv),
                ));
            }
        }
        let corner = |i: usize, j: usize| grid[row_start[i] + j];
        for i in 0..k {
            for j in 0..k - i {
                out.push([corner(i, j), corner(i + 1, j), corner(i, j + 1)]);
                if i + j + 1 < k {
                    out.push([corner(i + 1, j), corner(i + 1, j + 1), corner(i, j + 1)]);
                }
            }
        }
    }
    true
}
