//! Ground truth on the CPU: the indirect radiance of every receiver from every VPL, with the same
//! kernel (including the r_min clamp) as the GPU, summed in f64; without visibility (what every
//! GPU method approximates) or with exact visibility by ray tracing (what the light really
//! does). For small RSMs and images only. Beside it the direct light with each light's shadow
//! traced exactly, and the share of pixels whose direct shadow a GPU picture gets wrong.

use crate::frame::{Receiver, Vpl};
use crate::scene::{Light, LightKind, Scene};
use glam::{DVec3, Vec3};
use quadray_core::geom::{Bvh, ConvexPolygon, Ray};
use rayon::prelude::*;
use std::f64::consts::PI;

/// The CPU's one VPL kernel (the shaders' in WGSL): with `d` from the VPL to the receiver,
/// max(n_p . d, 0) max(-n . d, 0) / max(|d|^2, r_min^2)^2, which is cos_p cos / r^2 beyond
/// `r_min` and falls off as r^2 inside it. A VPL of flux F gives the receiver the irradiance
/// F / pi times this (a diffuse VPL's 1/pi).
pub fn vpl_kernel(d: DVec3, receiver_normal: DVec3, vpl_normal: DVec3, r_min: f64) -> f64 {
    let emit = vpl_normal.dot(d).max(0.0);
    let receive = (-receiver_normal.dot(d)).max(0.0);
    let r2 = d.length_squared().max(r_min * r_min);
    emit * receive / (r2 * r2)
}

pub use quadray_core::image_out::LUMINANCE;

/// The luminance of linear RGB `c` in f32, as the shaders weigh it
/// ([`quadray_core::image_out::luminance`]).
pub fn luminance(c: Vec3) -> f32 {
    quadray_core::image_out::luminance(c.to_array())
}

/// Indirect radiance albedo/pi * sum_p E_p at every receiver (zero where there is none), with
/// E_p = flux_p / pi * [`vpl_kernel`] (the spec's kernel with a diffuse VPL's 1/pi).
pub fn brute_force(vpls: &[Vpl], receivers: &[Option<Receiver>], r_min: f32) -> Vec<[f32; 3]> {
    sum_vpls(vpls, receivers, r_min, |_, _| true)
}

/// Rays a ground truth with visibility may trace (shaded pixels x VPLs): about a minute or two
/// on two cores.
pub const MAX_GROUND_TRUTH_RAYS: u64 = 1 << 30;

/// [`brute_force`] with each VPL's light reaching a receiver only where nothing of `scene` lies
/// between them: one ray per receiver and VPL that face each other.
pub fn ground_truth(vpls: &[Vpl], receivers: &[Option<Receiver>], scene: &Scene) -> Vec<[f32; 3]> {
    let visibility = Visibility::new(scene);
    sum_vpls(vpls, receivers, scene.r_min, |p, r| {
        visibility.between(p, r)
    })
}

/// `receivers` (a G-buffer's, seen from `eye`) with each albedo found anew on the CPU: at the
/// first triangle the ray from `eye` to the receiver meets, its vertices' albedo and texture
/// coordinate interpolated there and its base colour texture sampled as the raster passes sample
/// it ([`crate::scene::SceneTextures::sample`]): the albedo the G-buffer should hold, texel by
/// texel. A receiver no ray reaches keeps its own.
pub fn traced_receivers(
    receivers: &[Option<Receiver>],
    scene: &Scene,
    eye: Vec3,
) -> Vec<Option<Receiver>> {
    let visibility = Visibility::new(scene);
    receivers
        .par_iter()
        .map(|r| {
            let mut r = (*r)?;
            let to = Vec3::from(r.position) - eye;
            let ray = Ray::new(eye, to, 0.0, 1.0 + 1e-3);
            if let Some((id, t)) = visibility.bvh.closest(&visibility.polygons, &ray) {
                let triangle = &scene.triangles[id as usize];
                let w = barycentric(triangle.map(|v| Vec3::from(v.position)), eye + to * t);
                let mix = |f: &dyn Fn(&crate::scene::Vertex) -> Vec3| {
                    w[0] * f(&triangle[0]) + w[1] * f(&triangle[1]) + w[2] * f(&triangle[2])
                };
                let uv = mix(&|v| glam::Vec2::from(v.uv).extend(0.0)).truncate();
                let albedo = mix(&|v| Vec3::from(v.albedo));
                r.albedo = (albedo * scene.textures.sample(triangle[0].texture, uv)).to_array();
            }
            Some(r)
        })
        .collect()
}

/// The barycentric weights of `p` (in the triangle's plane) on the triangle's corners.
fn barycentric([a, b, c]: [Vec3; 3], p: Vec3) -> [f32; 3] {
    let (e1, e2, d) = (b - a, c - a, p - a);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d1, d2) = (d.dot(e1), d.dot(e2));
    let det = d11 * d22 - d12 * d12;
    let v = (d22 * d1 - d12 * d2) / det;
    let w = (d11 * d2 - d12 * d1) / det;
    [1.0 - v - w, v, w]
}

/// The scene's triangles in a BVH, for visibility between VPLs and receivers.
struct Visibility {
    polygons: Vec<ConvexPolygon>,
    bvh: Bvh,
    /// How far ray ends are lifted off their surfaces (world units).
    offset: f32,
}

impl Visibility {
    fn new(scene: &Scene) -> Self {
        let polygons: Vec<ConvexPolygon> = scene
            .triangles
            .iter()
            .map(|t| ConvexPolygon::new(t.iter().map(|v| Vec3::from(v.position)).collect()))
            .collect();
        Self {
            bvh: Bvh::build(&polygons),
            polygons,
            offset: 1e-3 * scene.extent(),
        }
    }

    /// Whether the segment between the VPL and the receiver, each end lifted along its normal,
    /// is free.
    fn between(&self, vpl: &Vpl, receiver: &Receiver) -> bool {
        let to = self.lift(vpl.position, vpl.normal);
        self.free(self.lift(receiver.position, receiver.normal), to)
    }

    /// `p` lifted off its surface along `n`.
    fn lift(&self, p: [f32; 3], n: [f32; 3]) -> Vec3 {
        Vec3::from(p) + self.offset * Vec3::from(n)
    }

    /// Whether nothing lies between `from` and `to`.
    fn free(&self, from: Vec3, to: Vec3) -> bool {
        if from.distance_squared(to) < self.offset * self.offset {
            return true;
        }
        !self
            .bvh
            .occluded(&self.polygons, &Ray::segment(from, to - from, 0.0), None)
    }
}

/// The sum of [`brute_force`] over the VPLs each receiver `visible` says it sees (asked only where
/// the kernel is not zero).
fn sum_vpls(
    vpls: &[Vpl],
    receivers: &[Option<Receiver>],
    r_min: f32,
    visible: impl Fn(&Vpl, &Receiver) -> bool + Sync,
) -> Vec<[f32; 3]> {
    let r_min = f64::from(r_min);
    let v = |a: [f32; 3]| Vec3::from(a).as_dvec3();
    receivers
        .par_iter()
        .map(|r| {
            let Some(receiver) = r else {
                return [0.0; 3];
            };
            let (x, n) = (v(receiver.position), v(receiver.normal));
            let mut e = DVec3::ZERO;
            for p in vpls {
                let g = vpl_kernel(x - v(p.position), n, v(p.normal), r_min);
                if g == 0.0 || !visible(p, receiver) {
                    continue;
                }
                e += v(p.flux) * (g / PI);
            }
            (v(receiver.albedo) / PI * e).as_vec3().to_array()
        })
        .collect()
}

/// The direct light of a scene's lights at every receiver, as the GPU's direct pass lights it
/// (albedo / pi times the irradiance facing the light times the cosine), without shadows and
/// with each light's shadow traced exactly.
#[derive(Clone, Debug)]
pub struct DirectTruth {
    /// Direct radiance with no shadows at all (zero where there is no receiver).
    pub unshadowed: Vec<[f32; 3]>,
    /// Direct radiance where a ray from the receiver (lifted off its surface) to each light
    /// (the sun: against its direction, out of the scene) meets nothing.
    pub shadowed: Vec<[f32; 3]>,
}

/// Where `light` lights `x` from (a point; the sun: a point out of the scene against its
/// direction, `reach` away) and its irradiance there on a surface facing it (W/m^2 per channel:
/// a spot's I(w) / d^2 within its cone, as `light.wgsl`'s `light_irradiance`).
fn light_at(light: &Light, x: Vec3, reach: f32) -> (Vec3, Vec3) {
    let intensity = light.intensity.radiometric();
    let from_point = |position: Vec3, edge: f32| {
        let d2 = x.distance_squared(position).max(1e-30);
        (position, intensity * edge / d2)
    };
    match light.kind {
        LightKind::Directional { direction } => (x - direction.normalize() * reach, intensity),
        LightKind::Point { position } => from_point(position, 1.0),
        LightKind::Spot { position, cone } => {
            let c = (x - position).normalize().dot(cone.direction.normalize());
            let outer = cone.cone_deg.to_radians().cos();
            let inner = (cone.cone_deg - cone.falloff_deg).to_radians().cos();
            let edge = if inner > outer {
                let t = ((c - outer) / (inner - outer)).clamp(0.0, 1.0);
                t * t * (3.0 - 2.0 * t)
            } else {
                f32::from(u8::from(c >= outer))
            };
            from_point(position, edge)
        }
    }
}

/// The direct light of `scene`'s first `max_lights` lights at every receiver, without shadows
/// and with each light's shadow traced ([`DirectTruth`]).
pub fn direct_truth(receivers: &[Option<Receiver>], scene: &Scene, max_lights: u32) -> DirectTruth {
    let visibility = Visibility::new(scene);
    let lights = &scene.lights[..scene.lights.len().min(max_lights as usize)];
    let reach = 2.0 * scene.extent();
    let (unshadowed, shadowed) = receivers
        .par_iter()
        .map(|r| {
            let Some(r) = r else {
                return ([0.0; 3], [0.0; 3]);
            };
            let (x, n, albedo) = (
                Vec3::from(r.position),
                Vec3::from(r.normal),
                Vec3::from(r.albedo),
            );
            let (mut all, mut seen) = (Vec3::ZERO, Vec3::ZERO);
            for light in lights {
                let (from, irradiance) = light_at(light, x, reach);
                let cos = n.dot((from - x).normalize_or_zero());
                if cos <= 0.0 {
                    continue;
                }
                let l = albedo / std::f32::consts::PI * irradiance * cos;
                all += l;
                if visibility.free(visibility.lift(r.position, r.normal), from) {
                    seen += l;
                }
            }
            (all.to_array(), seen.to_array())
        })
        .unzip();
    DirectTruth {
        unshadowed,
        shadowed,
    }
}

/// The share of the receivers the direct light reaches (unshadowed luminance above zero) whose
/// shadow `direct` (a GPU picture's direct light) gets wrong: where its light differs from the
/// traced shadow's by more than half the unshadowed light, i.e. where the GPU's visibility (its
/// light over the unshadowed) rounded to lit or shadowed is not the traced one. A soft edge a
/// pixel wide counts only where it is more than half wrong.
pub fn shadow_mismatch(direct: &[[f32; 3]], truth: &DirectTruth) -> f64 {
    assert_eq!(
        direct.len(),
        truth.shadowed.len(),
        "images of different sizes"
    );
    let lum = |c: &[f32; 3]| luminance(Vec3::from(*c));
    let (mut reached, mut wrong) = (0u64, 0u64);
    for ((gpu, seen), all) in direct.iter().zip(&truth.shadowed).zip(&truth.unshadowed) {
        let all = lum(all);
        if all <= 0.0 {
            continue;
        }
        reached += 1;
        if (lum(gpu) - lum(seen)).abs() > 0.5 * all {
            wrong += 1;
        }
    }
    wrong as f64 / reached.max(1) as f64
}

/// Error of an image against a reference (both linear RGB, same size).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ImageError {
    /// Root mean square of the differences over every pixel and channel.
    pub rmse: f64,
    /// sum |a - b| / sum |b| over every pixel and channel.
    pub rel_l1: f64,
    /// max |a - b| / max |b|.
    pub rel_max: f64,
}

/// How far `image` is from `reference`; panics when their sizes differ.
pub fn compare(image: &[[f32; 3]], reference: &[[f32; 3]]) -> ImageError {
    assert_eq!(image.len(), reference.len(), "images of different sizes");
    let (mut sq, mut abs, mut norm, mut max_diff, mut max_ref) = (0.0, 0.0, 0.0, 0.0f64, 0.0f64);
    for (a, b) in image.iter().flatten().zip(reference.iter().flatten()) {
        let (a, b) = (f64::from(*a), f64::from(*b));
        sq += (a - b).powi(2);
        abs += (a - b).abs();
        norm += b.abs();
        max_diff = max_diff.max((a - b).abs());
        max_ref = max_ref.max(b.abs());
    }
    let count = (image.len() * 3).max(1) as f64;
    ImageError {
        rmse: (sq / count).sqrt(),
        rel_l1: if norm > 0.0 { abs / norm } else { abs },
        rel_max: if max_ref > 0.0 {
            max_diff / max_ref
        } else {
            max_diff
        },
    }
}

/// Per-pixel relative error |a - b| summed over channels / (mean |b| per pixel), for heat maps.
pub fn error_map(image: &[[f32; 3]], reference: &[[f32; 3]]) -> Vec<f32> {
    let mean: f32 =
        reference.iter().flatten().map(|v| v.abs()).sum::<f32>() / reference.len().max(1) as f32;
    image
        .iter()
        .zip(reference)
        .map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).abs()).sum::<f32>() / mean.max(1e-20))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_vpl_facing_a_receiver_gives_the_inverse_square_law() {
        // VPL at the origin facing +z, receiver at distance 2 facing back: cosines 1,
        // E = flux / (4 pi), radiance = albedo / pi * E
        let vpl = Vpl {
            flux: [4.0, 8.0, 0.0],
            position: [0.0; 3],
            normal: [0.0, 0.0, 1.0],
        };
        let receiver = Receiver {
            position: [0.0, 0.0, 2.0],
            normal: [0.0, 0.0, -1.0],
            albedo: [1.0, 0.5, 1.0],
        };
        let out = brute_force(&[vpl], &[Some(receiver), None], 0.1);
        let pi = std::f32::consts::PI;
        assert!((out[0][0] - 1.0 / (pi * pi)).abs() < 1e-6);
        assert!((out[0][1] - 1.0 / (pi * pi)).abs() < 1e-6);
        assert_eq!(out[1], [0.0; 3]);
        // closer than r_min the 1/r^4 is clamped: d = 0.05, r_min = 0.1 -> d^2 / r_min^4 = 0.25
        let near = Receiver {
            position: [0.0, 0.0, 0.05],
            ..receiver
        };
        let out = brute_force(&[vpl], &[Some(near)], 0.1);
        assert!((out[0][0] - 4.0 * 0.0025 / 1e-4 / (pi * pi)).abs() < 1e-3);
    }

    #[test]
    fn the_ground_truth_drops_exactly_the_vpls_an_occluder_hides() {
        // two VPLs facing a receiver at distance 2; a small square at z = 1 hides only the first
        let vpls = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]].map(|position| Vpl {
            flux: [1.0; 3],
            position,
            normal: [0.0, 0.0, 1.0],
        });
        let receiver = Some(Receiver {
            position: [0.0, 0.0, 2.0],
            normal: [0.0, 0.0, -1.0],
            albedo: [1.0; 3],
        });
        let vertex = |x: f32, y: f32| {
            crate::scene::Vertex::untextured([x, y, 1.0], [0.0, 0.0, 1.0], [1.0; 3])
        };
        let mut scene = crate::Scene::cornell();
        scene.triangles = vec![
            [vertex(-0.2, -0.2), vertex(0.2, -0.2), vertex(0.2, 0.2)],
            [vertex(-0.2, -0.2), vertex(0.2, 0.2), vertex(-0.2, 0.2)],
        ];
        let truth = ground_truth(&vpls, &[receiver, None], &scene);
        let second = brute_force(&vpls[1..], &[receiver], scene.r_min);
        assert!(second[0][0] > 0.0);
        assert_eq!(truth[0], second[0], "only the second VPL is seen");
        assert_eq!(truth[1], [0.0; 3]);
        // moved behind the receiver, the square hides nothing
        for v in scene.triangles.iter_mut().flatten() {
            v.position[2] = 3.0;
        }
        let all = brute_force(&vpls, &[receiver], scene.r_min);
        assert_eq!(ground_truth(&vpls, &[receiver], &scene)[0], all[0]);
    }

    #[test]
    fn errors_of_a_scaled_image() {
        let reference = vec![[1.0, 2.0, 3.0]; 4];
        let scaled: Vec<_> = reference.iter().map(|p| p.map(|v| v * 1.1)).collect();
        let e = compare(&scaled, &reference);
        assert!((e.rel_l1 - 0.1).abs() < 1e-6);
        assert!((e.rel_max - 0.1).abs() < 1e-6);
        assert_eq!(compare(&reference, &reference).rmse, 0.0);
    }
}
