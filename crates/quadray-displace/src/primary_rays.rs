//! The CPU's own primary rays: for each pixel, the tangent-space ray the renderer should trace,
//! built in double precision from the camera, the surface's triangles and its tangent frame,
//! never from anything the GPU computed. The ground truth traces these rays, so a wrong camera, a
//! wrong tangent frame or a wrong texture-space transform on the GPU shows up as wrong hits, and
//! [`crate::accuracy::RayAgreement`] names the pixel whose GPU ray differs.

use crate::heightmap::HeightMap;
use crate::reference::{Hit, Ray, bilinear_depth};
use crate::scene::{Plane, SurfaceKind, Vertex, View, mesh_grid};
use crate::{DisplaceError, Settings};
use glam::{DMat4, DVec2, DVec3, DVec4};
use rayon::prelude::*;

/// The renderer discards a fragment whose view direction makes a smaller cosine than this with
/// the polygon's normal (it sees the polygon edge-on or from behind), and a light this low
/// reaches nothing, as `surface.wgsl` has it.
pub const MIN_COSINE: f64 = 1.0e-4;

/// One pixel's view ray where it meets the surface's polygon.
#[derive(Clone, Copy, Debug)]
pub struct PixelRay {
    /// The tangent-space ray (on a wrapped surface, p0 within the repeat it starts in).
    pub ray: Ray,
    /// The world point where the view ray meets the polygon.
    pub world: DVec3,
    /// Unit tangent (+u), bitangent (+v) and normal there.
    pub frame: [DVec3; 3],
}

impl PixelRay {
    /// The world point of a hit of this ray (`hit.uv` on the ray's own repeat), `tile_world`
    /// world units a repeat, depths scaled by `depth_scale`.
    pub fn world_at(&self, hit: Hit, depth_scale: f64, tile_world: f64) -> DVec3 {
        let [t, b, n] = self.frame;
        let along = hit.uv - self.ray.p0;
        self.world + (t * along.x + b * along.y - n * hit.z * depth_scale) * tile_world
    }
}

/// The tangent-space ray towards `towards` (a unit vector in tangent space): uv change per unit
/// of depth, as `ray_slope` in `trace.wgsl`.
pub fn ray_slope(towards: DVec3, depth_scale: f64) -> DVec2 {
    -towards.truncate() / towards.z * depth_scale
}

/// Every pixel's ray for `kind` drawn with `s`, row by row from the top (None: the pixel shows
/// no surface): the nearest of the surface's triangles that faces the camera (as the depth test
/// and the renderer's discard leave it), its attributes at the exact intersection (what
/// perspective-correct interpolation gives).
pub fn camera_rays(kind: SurfaceKind, s: &Settings) -> Vec<Option<PixelRay>> {
    camera_rays_as(kind, s, |ray| ray)
}

/// [`camera_rays`], keeping of each only what `keep` takes from it (the ground truth keeps the
/// tangent-space ray alone: a third of the memory on a large frame).
pub fn camera_rays_as<T: Send>(
    kind: SurfaceKind,
    s: &Settings,
    keep: impl Fn(PixelRay) -> T + Sync,
) -> Vec<Option<T>> {
    let view = View::of(kind, s);
    let eye = view.eye.as_dvec3();
    let vertices = kind.vertices();
    let triangles: Vec<[DVec3; 3]> = vertices
        .chunks_exact(3)
        .map(|t| [0, 1, 2].map(|k| DVec3::from(t[k].position.map(f64::from))))
        .collect();
    let plane = kind.is_planar().then(|| Plane::of(kind));
    let depth_scale = f64::from(s.depth_scale);
    rasterise(&triangles, &view, s, |i, world, weights| {
        let (uv, frame) = match &plane {
            Some(plane) => planar_attributes(plane, world),
            None => interpolated_attributes(&vertices[i * 3..i * 3 + 3], weights),
        };
        let to_eye = (eye - world).normalize();
        let v = DVec3::new(
            to_eye.dot(frame[0]),
            to_eye.dot(frame[1]),
            to_eye.dot(frame[2]),
        );
        (v.z > MIN_COSINE).then(|| {
            let p0 = if kind.wraps() { uv - uv.floor() } else { uv };
            let ray = Ray {
                p0,
                e: ray_slope(v, depth_scale),
            };
            keep(PixelRay { ray, world, frame })
        })
    })
}

/// The displaced-mesh baseline's exact hits: each pixel's ray against the same grid of
/// triangles the mesh draws (one quad per texel of the map's longer side per repeat, vertices on
/// the bilinear surface), the hit's uv and depth interpolated from the triangle's corners.
/// Refused above [`MAX_MESH_TRIANGLES`] (a tiled wall of a 1024^2 map has 134 million).
pub fn mesh_hits(
    map: &HeightMap,
    kind: SurfaceKind,
    s: &Settings,
) -> Result<Vec<Option<Hit>>, DisplaceError> {
    let side = u64::from(mesh_grid(map.width, map.height)) * u64::from(kind.tiles());
    if 2 * side * side > MAX_MESH_TRIANGLES {
        return Err(DisplaceError::Settings(format!(
            "the mesh ground truth would test {} triangles (at most {MAX_MESH_TRIANGLES})",
            2 * side * side
        )));
    }
    let view = View::of(kind, s);
    let plane = Plane::of(kind);
    let (origin, u, v) = (
        plane.origin.as_dvec3(),
        plane.u.as_dvec3(),
        plane.v.as_dvec3(),
    );
    let down = -plane.normal().as_dvec3() * f64::from(s.depth_scale) * f64::from(kind.tile_world());
    let grid = mesh_grid(map.width, map.height);
    let addressing = kind.addressing();
    let corner = |i: u32, j: u32| {
        let uv = DVec2::new(f64::from(i), f64::from(j)) / f64::from(grid);
        let depth = bilinear_depth(map, addressing, uv);
        (uv, depth, origin + u * uv.x + v * uv.y + down * depth)
    };
    let side = grid * kind.tiles();
    let corners: Vec<_> = (0..=side)
        .flat_map(|j| (0..=side).map(move |i| (i, j)))
        .map(|(i, j)| corner(i, j))
        .collect();
    let at = |i: u32, j: u32| corners[(j * (side + 1) + i) as usize];
    let quads = (0..side).flat_map(|j| (0..side).map(move |i| (i, j)));
    let mut triangles = Vec::new();
    let mut attributes = Vec::new();
    for (i, j) in quads {
        let [a, b, c, d] = [at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)];
        for t in [[a, b, c], [c, b, d]] {
            triangles.push(t.map(|(_, _, world)| world));
            attributes.push(t.map(|(uv, depth, _)| (uv, depth)));
        }
    }
    Ok(rasterise(&triangles, &view, s, |i, _, weights| {
        let (uv, z) = (0..3).fold((DVec2::ZERO, 0.0), |(uv, z), k| {
            let (corner_uv, depth) = attributes[i][k];
            (uv + corner_uv * weights[k], z + depth * weights[k])
        });
        Some(Hit { uv, z })
    }))
}

/// The most triangles [`mesh_hits`] intersects.
pub const MAX_MESH_TRIANGLES: u64 = 1 << 22;

/// For each pixel of the frame `s` asks for, row by row from the top: the ray through its centre
/// against `triangles` (world positions), `hit(triangle, point, barycentric weights)` of the
/// nearest triangle it accepts. The CPU's own rasteriser: each triangle is tested only on the
/// pixels its projection may cover.
fn rasterise<T: Send>(
    triangles: &[[DVec3; 3]],
    view: &View,
    s: &Settings,
    hit: impl Fn(usize, DVec3, [f64; 3]) -> Option<T> + Sync,
) -> Vec<Option<T>> {
    let (width, height) = (s.size.width, s.size.height);
    let view_proj = view.view_proj.as_dmat4();
    let inverse = view_proj.inverse();
    let bounds: Vec<PixelBounds> = triangles
        .iter()
        .map(|t| PixelBounds::of(t, &view_proj, width, height))
        .collect();
    (0..height)
        .into_par_iter()
        .flat_map_iter(|y| {
            let (bounds, hit) = (&bounds, &hit);
            let row: Vec<usize> = (0..triangles.len())
                .filter(|&i| bounds[i].rows.contains(&y))
                .collect();
            (0..width).map(move |x| {
                let (origin, direction) = pixel_ray(&inverse, [x, y], [width, height]);
                let mut nearest: Option<(f64, T)> = None;
                for &i in row.iter().filter(|&&i| bounds[i].columns.contains(&x)) {
                    let Some((t, weights)) = intersect_triangle(origin, direction, &triangles[i])
                    else {
                        continue;
                    };
                    if nearest.as_ref().is_some_and(|(best, _)| *best <= t) {
                        continue;
                    }
                    if let Some(found) = hit(i, origin + direction * t, weights) {
                        nearest = Some((t, found));
                    }
                }
                nearest.map(|(_, found)| found)
            })
        })
        .collect()
}

/// The world ray through the centre of pixel `[x, y]` (rows from the top) of a `[width, height]`
/// frame: from the near plane, towards the far plane.
fn pixel_ray(inverse: &DMat4, [x, y]: [u32; 2], [width, height]: [u32; 2]) -> (DVec3, DVec3) {
    let ndc_x = (f64::from(x) + 0.5) / f64::from(width) * 2.0 - 1.0;
    let ndc_y = 1.0 - (f64::from(y) + 0.5) / f64::from(height) * 2.0;
    let unproject = |z: f64| {
        let p = *inverse * DVec4::new(ndc_x, ndc_y, z, 1.0);
        p.truncate() / p.w
    };
    let near = unproject(0.0);
    (near, unproject(1.0) - near)
}

/// The pixels a triangle may cover (every pixel when it reaches behind the camera).
struct PixelBounds {
    rows: std::ops::RangeInclusive<u32>,
    columns: std::ops::RangeInclusive<u32>,
}

impl PixelBounds {
    fn of(triangle: &[DVec3; 3], view_proj: &DMat4, width: u32, height: u32) -> Self {
        let clip = triangle.map(|p| *view_proj * p.extend(1.0));
        if clip.iter().any(|c| c.w <= 1e-9) {
            return Self {
                rows: 0..=height - 1,
                columns: 0..=width - 1,
            };
        }
        let pixel = clip.map(|c| {
            DVec2::new(
                (c.x / c.w + 1.0) / 2.0 * f64::from(width),
                (1.0 - c.y / c.w) / 2.0 * f64::from(height),
            )
        });
        let lo = pixel[0].min(pixel[1]).min(pixel[2]);
        let hi = pixel[0].max(pixel[1]).max(pixel[2]);
        // Pixel i's centre is at i + 0.5; one pixel of margin either side.
        let span = |lo: f64, hi: f64, n: u32| {
            let first = (lo - 1.5).floor().clamp(0.0, f64::from(n)) as u32;
            let last = (hi + 0.5).ceil().clamp(0.0, f64::from(n - 1)) as u32;
            first..=last
        };
        Self {
            rows: span(lo.y, hi.y, height),
            columns: span(lo.x, hi.x, width),
        }
    }
}

/// Möller-Trumbore: the distance along `direction` (in its lengths) and the barycentric weights
/// of the hit, for hits in front of `origin`, from either side.
fn intersect_triangle(
    origin: DVec3,
    direction: DVec3,
    &[a, b, c]: &[DVec3; 3],
) -> Option<(f64, [f64; 3])> {
    let (ab, ac) = (b - a, c - a);
    let p = direction.cross(ac);
    let det = ab.dot(p);
    if det.abs() < 1e-300 {
        return None;
    }
    let to_origin = origin - a;
    let u = to_origin.dot(p) / det;
    let q = to_origin.cross(ab);
    let v = direction.dot(q) / det;
    let t = ac.dot(q) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0).then_some((t, [1.0 - u - v, u, v]))
}

/// A planar surface's uv and frame from its plane alone: one repeat per `plane.u`, `plane.v`.
fn planar_attributes(plane: &Plane, world: DVec3) -> (DVec2, [DVec3; 3]) {
    let (u, v) = (plane.u.as_dvec3(), plane.v.as_dvec3());
    let offset = world - plane.origin.as_dvec3();
    let uv = DVec2::new(
        offset.dot(u) / u.length_squared(),
        offset.dot(v) / v.length_squared(),
    );
    (
        uv,
        [u.normalize(), v.normalize(), plane.normal().as_dvec3()],
    )
}

/// A mesh's uv and frame at barycentric `weights`: its normals and (MikkTSpace) tangents
/// interpolated, the bitangent of each vertex w * (N x T) as glTF defines it.
fn interpolated_attributes(triangle: &[Vertex], weights: [f64; 3]) -> (DVec2, [DVec3; 3]) {
    let mix = |f: &dyn Fn(&Vertex) -> DVec3| {
        (0..3).fold(DVec3::ZERO, |sum, i| sum + f(&triangle[i]) * weights[i])
    };
    let vec3 = |a: [f32; 3]| DVec3::from(a.map(f64::from));
    let uv = mix(&|v| vec3([v.uv[0], v.uv[1], 0.0])).truncate();
    let normal = mix(&|v| vec3(v.normal));
    let tangent = mix(&|v| vec3([v.tangent[0], v.tangent[1], v.tangent[2]]));
    let bitangent = mix(&|v| {
        vec3(v.normal).cross(vec3([v.tangent[0], v.tangent[1], v.tangent[2]]))
            * f64::from(v.tangent[3])
    });
    (
        uv,
        [
            tangent.normalize(),
            bitangent.normalize(),
            normal.normalize(),
        ],
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use quadray_core::settings::Size;

    /// The torus's MikkTSpace tangents follow the surface's own parameter directions: +u around
    /// the ring, +v around the tube (a flipped sign or a swapped axis would trace every ray the
    /// wrong way).
    #[test]
    fn torus_tangent_frame_follows_the_parameter_directions() {
        let (ring, tube) = (1.0f64, 0.4f64);
        let mut worst = 0.0f64;
        for v in SurfaceKind::Torus.vertices() {
            let a = f64::from(v.uv[0]) / 4.0 * std::f64::consts::TAU;
            let b = f64::from(v.uv[1]) * std::f64::consts::TAU;
            let d_du = DVec3::new(-a.sin(), 0.0, a.cos()) * (ring + tube * b.cos());
            let d_dv = DVec3::new(-a.cos() * b.sin(), b.cos(), -a.sin() * b.sin()) * tube;
            let (_, [t, bt, _]) = interpolated_attributes(&[v, v, v], [1.0, 0.0, 0.0]);
            worst = worst
                .max(t.angle_between(d_du).to_degrees())
                .max(bt.angle_between(d_dv).to_degrees());
        }
        assert!(worst < 5.0, "tangent frame off by {worst} degrees");
    }

    /// Straight down on the wall: the ray through the frame's centre starts at the wall's
    /// centre (a repeat corner: uv 0) and goes straight down; every pixel shows the wall.
    #[test]
    fn a_vertical_view_of_the_wall_sees_straight_down_at_the_centre() {
        let s = Settings {
            view_angle_deg: 0.0,
            size: Size::new(2, 2),
            ..Default::default()
        };
        let rays = camera_rays(SurfaceKind::Wall, &s);
        assert!(rays.iter().all(Option::is_some));
        let centre = rays
            .iter()
            .flatten()
            .map(|r| r.world)
            .fold(DVec3::ZERO, |a, b| a + b / 4.0);
        assert!(centre.length() < 1e-9, "{centre}");
        for r in rays.iter().flatten() {
            assert!(r.ray.e.length() < 0.1, "{:?}", r.ray);
        }
    }
}
