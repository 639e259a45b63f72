//! The lights as the passes see them: each light's reflective shadow maps as views (a spot or a
//! directional light one, a point light six, one per cube face), plain values a renderer fills
//! from its own scene, and the per-view uniforms made from them (the light itself, the gather's
//! per-light terms).

use crate::contract::{LightTermsUniform, LightUniform, RasterUniform, ShadowUniform};
use crate::scene::{Light, LightKind, Scene, extent_of};
use crate::settings::Settings;
use glam::{DMat4, Mat4, Vec2, Vec3, Vec4};

/// How an RSM view projects the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// From a point, a square frustum of this full field of view (degrees): a spot's twice its
    /// cone, a point light's cube face 90.
    Perspective {
        /// Full field of view across (and down) the map.
        fov_deg: f32,
    },
    /// Parallel rays over a square this wide (world units): a directional light's.
    Orthographic {
        /// Side of the square the map covers, across the light's direction.
        width: f32,
    },
}

/// One reflective shadow map of a light: its projection, and the light's emission as that map
/// sees it. A point light's six faces are six views; the gather sums the views' light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightView {
    /// World -> light clip space: the RSM's projection.
    pub view_proj: Mat4,
    /// Where the view looks from: the light, or for a directional light the middle of the map's
    /// near plane.
    pub position: Vec3,
    /// Unit axis of the view (a spot's cone axis, a cube face's normal, the sun's direction).
    pub direction: Vec3,
    /// How the map projects.
    pub projection: Projection,
    /// A spot's cone: half-angle and falloff width (degrees); `None` lights the whole map.
    pub cone: Option<(f32, f32)>,
    /// Radiant intensity (W/sr per channel; a spot's on its axis), or for a directional light
    /// the irradiance of a surface facing it (W/m^2).
    pub intensity: [f32; 3],
    /// The scene's size (its bounds' diagonal): the unit of RSM depth, in which the validity
    /// thresholds are given.
    pub extent: f32,
    /// The view's far plane: everything lit is closer.
    pub far: f32,
}

/// The six faces of a cube map: axis and up.
const CUBE_FACES: [(Vec3, Vec3); 6] = [
    (Vec3::X, Vec3::NEG_Y),
    (Vec3::NEG_X, Vec3::NEG_Y),
    (Vec3::Y, Vec3::Z),
    (Vec3::NEG_Y, Vec3::NEG_Z),
    (Vec3::Z, Vec3::NEG_Y),
    (Vec3::NEG_Z, Vec3::NEG_Y),
];

impl LightView {
    /// The views of a quadray [`Scene`]'s first `max_lights` lights, in order.
    pub fn of_scene(scene: &Scene, max_lights: u32) -> Vec<Self> {
        let bounds = scene.bounds();
        scene
            .lights
            .iter()
            .take(max_lights as usize)
            .flat_map(|l| Self::of_light(l, bounds))
            .collect()
    }

    /// `light` (its intensity radiometric: [`crate::scene::Intensity::radiometric`]) over
    /// geometry within `bounds` (min, max): for a renderer that keeps its own scene. A
    /// directional light's map is fitted to the bounds, not to the camera's view: a moving
    /// camera changes nothing in it (no shimmer, nothing to snap to texels), for texels spent on
    /// parts of the scene the camera may not see.
    pub fn of_light(light: &Light, bounds: (Vec3, Vec3)) -> Vec<Self> {
        let intensity = light.intensity.radiometric().to_array();
        let extent = extent_of(bounds);
        let centre = bounds.0.midpoint(bounds.1);
        let perspective = |position: Vec3, direction: Vec3, up: Vec3, fov_deg: f32, cone| {
            let far = position.distance(centre) + extent;
            let view = Mat4::look_to_rh(position, direction, up);
            let proj = Mat4::perspective_rh(fov_deg.to_radians(), 1.0, far * 1e-3, far);
            Self {
                view_proj: proj * view,
                position,
                direction,
                projection: Projection::Perspective { fov_deg },
                cone,
                intensity,
                extent,
                far,
            }
        };
        match light.kind {
            LightKind::Spot { position, cone } => {
                let direction = cone.direction.normalize();
                let up = if direction.y.abs() > 0.99 {
                    Vec3::Z
                } else {
                    Vec3::Y
                };
                vec![perspective(
                    position,
                    direction,
                    up,
                    2.0 * cone.cone_deg,
                    Some((cone.cone_deg, cone.falloff_deg)),
                )]
            }
            LightKind::Point { position } => CUBE_FACES
                .iter()
                .map(|&(axis, up)| perspective(position, axis, up, 90.0, None))
                .collect(),
            LightKind::Directional { direction } => {
                vec![Self::orthographic(direction.normalize(), bounds, intensity)]
            }
        }
    }

    /// A directional light's RSM view: the bounds' corners in the light's frame, a square over
    /// them.
    fn orthographic(direction: Vec3, bounds: (Vec3, Vec3), intensity: [f32; 3]) -> Self {
        Self::orthographic_over(direction, &corners(bounds), bounds, intensity, None)
    }

    /// A directional light's view over `receivers` (world points): a square over them across the
    /// light, from in front of every caster within `bounds` to behind the receivers. With a
    /// shadow map's side, the square's width is rounded up to a step of the scene's size and its
    /// middle moved to a whole texel of a frame fixed to the scene, so that a map fitted to a
    /// moving camera keeps its texels on the same world points while its width holds (no
    /// shimmering edges).
    fn orthographic_over(
        direction: Vec3,
        receivers: &[Vec3],
        bounds: (Vec3, Vec3),
        intensity: [f32; 3],
        snap_to_texels: Option<u32>,
    ) -> Self {
        let (lo, hi) = bounds;
        let extent = extent_of(bounds);
        let centre = lo.midpoint(hi);
        let up = if direction.y.abs() > 0.99 {
            Vec3::Z
        } else {
            Vec3::Y
        };
        let at_centre = Mat4::look_to_rh(centre, direction, up);
        let span = |points: &mut dyn Iterator<Item = Vec3>| {
            points.fold((Vec3::MAX, Vec3::MIN), |(a, b), c| {
                let p = at_centre.transform_point3(c);
                (a.min(p), b.max(p))
            })
        };
        let (min, max) = span(&mut receivers.iter().copied());
        // casters lie anywhere in the bounds towards the light
        let (_, casters_max) = span(&mut corners(bounds).into_iter());
        let max = Vec3::new(max.x, max.y, max.z.max(casters_max.z));
        // square, centred on the receivers' box, a little wider so its edge texels see geometry
        let mut width = (max.x - min.x).max(max.y - min.y).max(1e-3) * 1.02;
        let mut across = Vec2::new(min.x + max.x, min.y + max.y) * 0.5;
        if let Some(size) = snap_to_texels {
            let step = extent / 64.0;
            width = (width / step).ceil() * step;
            let texel = width / size as f32;
            across = (across / texel).round() * texel;
        }
        let middle = at_centre
            .inverse()
            .transform_point3(Vec3::new(across.x, across.y, 0.0));
        // the view looks down -z: the nearest point is at z = max.z
        let margin = 0.01 * extent;
        let position = middle - direction * (max.z + margin);
        let far = max.z - min.z + 2.0 * margin;
        let half = width * 0.5;
        let view = Mat4::look_to_rh(position, direction, up);
        Self {
            view_proj: Mat4::orthographic_rh(-half, half, -half, half, 0.0, far) * view,
            position,
            direction,
            projection: Projection::Orthographic { width },
            cone: None,
            intensity,
            extent,
            far,
        }
    }

    /// The view of this light view's shadow map of `size`^2 texels for the direct light: a
    /// directional light's fitted to the part of `bounds` (the scene's) inside the camera's
    /// frustum (`camera_view_proj`, world -> clip with depth 0..1), which holds every receiver
    /// the camera sees, as engines fit a cascade; a spot's and a point light's face are the RSM's
    /// view (the cone, a cube face), only with more texels.
    pub(crate) fn shadow_view(
        &self,
        camera_view_proj: Mat4,
        bounds: (Vec3, Vec3),
        size: u32,
    ) -> Self {
        match self.projection {
            Projection::Perspective { .. } => *self,
            Projection::Orthographic { .. } => {
                let seen = visible_region(camera_view_proj, bounds);
                if seen.is_empty() {
                    return *self;
                }
                Self::orthographic_over(self.direction, &seen, bounds, self.intensity, Some(size))
            }
        }
    }

    /// The direct pass's uniform of this view as the view of a shadow map of `size`^2 texels.
    /// The raster passes' uniform for drawing this view (the RSM, a shadow map): its
    /// projection with depth reversed, and its position.
    pub(crate) fn raster_uniform(&self) -> RasterUniform {
        let p = self.position;
        RasterUniform {
            view_proj: reversed_depth(self.view_proj).to_cols_array_2d(),
            eye: [p.x, p.y, p.z, 1.0],
        }
    }

    pub(crate) fn shadow_uniform(&self, size: u32) -> ShadowUniform {
        let parallel = matches!(self.projection, Projection::Orthographic { .. });
        ShadowUniform {
            // as the shadow map was drawn (`reversed_depth`)
            view_proj: reversed_depth(self.view_proj).to_cols_array_2d(),
            texel: [
                self.texel_measure(size).sqrt(),
                f32::from(u8::from(parallel)),
                size as f32,
                0.0,
            ],
        }
    }

    /// An RSM texel's measure on the axis: its solid angle (perspective; it shrinks as cos^3
    /// off the axis) or its area across the light (orthographic).
    pub(crate) fn texel_measure(&self, rsm_size: u32) -> f32 {
        let side = match self.projection {
            Projection::Perspective { fov_deg } => {
                2.0 * (0.5 * fov_deg).to_radians().tan() / rsm_size as f32
            }
            Projection::Orthographic { width } => width / rsm_size as f32,
        };
        side * side
    }

    /// The gather's per-view values for `settings`, with the clamp `r_min` of the VPL kernel's
    /// 1/r^4 (world units) and where the view's low-resolution samples start (0 for the first
    /// view of a frame, which writes the radiance the others add to).
    pub(crate) fn terms(
        &self,
        settings: &Settings,
        r_min: f32,
        low_offset: u32,
    ) -> LightTermsUniform {
        LightTermsUniform {
            r_min,
            plane_agreement: 0.02 * self.extent,
            shadow_thickness: settings.shadow_thickness * self.extent,
            low_offset,
        }
    }

    /// The view's uniform for an `rsm_size`^2 RSM.
    pub(crate) fn uniform(&self, rsm_size: u32) -> LightUniform {
        let (p, d, i) = (self.position, self.direction, self.intensity);
        // no cone: every direction in front of the map counts (cos >= -1)
        let (outer, inner) = self.cone.map_or((-1.0, -1.0), |(cone_deg, falloff_deg)| {
            let cone = cone_deg.to_radians();
            (cone.cos(), (cone - falloff_deg.to_radians()).cos())
        });
        let parallel = matches!(self.projection, Projection::Orthographic { .. });
        LightUniform {
            view_proj: self.view_proj.to_cols_array_2d(),
            inv_view_proj: relative_inverse(self.view_proj, p).to_cols_array_2d(),
            position: [p.x, p.y, p.z, 1.0 / self.extent],
            direction: [d.x, d.y, d.z, outer],
            intensity: [i[0], i[1], i[2], inner],
            parallel: [
                f32::from(u8::from(parallel)),
                self.texel_measure(rsm_size),
                0.0,
                0.0,
            ],
        }
    }
}

/// The eight corners of `bounds` (min, max); corner `i` takes max on x, y, z where bits 0, 1, 2
/// of `i` are set.
fn corners((lo, hi): (Vec3, Vec3)) -> [Vec3; 8] {
    std::array::from_fn(|i| {
        let pick = |bit: usize, a: f32, b: f32| if i & bit == 0 { a } else { b };
        Vec3::new(
            pick(1, lo.x, hi.x),
            pick(2, lo.y, hi.y),
            pick(4, lo.z, hi.z),
        )
    })
}

/// The six faces of a hexahedron whose corners are numbered as [`corners`]', each a cycle of
/// four corners.
fn faces(c: &[Vec3; 8]) -> [[Vec3; 4]; 6] {
    std::array::from_fn(|f| {
        let (axis, side) = (f / 2, (f % 2) << (f / 2));
        let (i, j) = (1 << ((axis + 1) % 3), 1 << ((axis + 2) % 3));
        [side, side | i, side | i | j, side | j].map(|k| c[k])
    })
}

/// The planes of a convex hexahedron's faces, as (normal, offset) with `normal . p + offset >= 0`
/// inside.
fn inner_planes(c: &[Vec3; 8]) -> Vec<(Vec3, f32)> {
    let middle = c.iter().copied().sum::<Vec3>() / 8.0;
    faces(c)
        .iter()
        .filter_map(|f| {
            let n = (f[1] - f[0]).cross(f[3] - f[0]).try_normalize()?;
            let n = if n.dot(middle - f[0]) < 0.0 { -n } else { n };
            Some((n, -n.dot(f[0])))
        })
        .collect()
}

/// `polygon` clipped to the inside of every one of `planes` (Sutherland-Hodgman).
fn clip(polygon: &[Vec3], planes: &[(Vec3, f32)]) -> Vec<Vec3> {
    let mut out = polygon.to_vec();
    for &(n, d) in planes {
        let input = std::mem::take(&mut out);
        for (k, &a) in input.iter().enumerate() {
            let b = input[(k + 1) % input.len()];
            let (da, db) = (n.dot(a) + d, n.dot(b) + d);
            if da >= 0.0 {
                out.push(a);
            }
            if (da >= 0.0) != (db >= 0.0) {
                out.push(a + (b - a) * (da / (da - db)));
            }
        }
    }
    out
}

/// The corners of the part of `bounds` inside the camera's frustum (`view_proj`: world -> clip
/// with depth 0..1): every vertex of the two solids' intersection lies on a face of one clipped
/// to the other. Empty where they do not meet; the whole bounds where the frustum has no finite
/// far corners.
fn visible_region(view_proj: Mat4, bounds: (Vec3, Vec3)) -> Vec<Vec3> {
    let inverse = view_proj.inverse();
    let ndc = corners((Vec3::new(-1.0, -1.0, 0.0), Vec3::ONE));
    let frustum = ndc.map(|p| inverse * p.extend(1.0));
    if frustum
        .iter()
        .any(|p| !(p.w.abs() > 1e-12 && p.is_finite()))
    {
        return corners(bounds).to_vec();
    }
    let frustum = frustum.map(|p| p.truncate() / p.w);
    let solid = corners(bounds);
    let (frustum_planes, solid_planes) = (inner_planes(&frustum), inner_planes(&solid));
    let from_frustum = faces(&frustum).into_iter().map(|f| clip(&f, &solid_planes));
    let from_solid = faces(&solid).into_iter().map(|f| clip(&f, &frustum_planes));
    from_frustum.chain(from_solid).flatten().collect()
}

/// `view_proj` with its depth reversed (clip z -> w - z: 1 at the near plane, 0 at the far), as
/// quadray's raster passes draw: a float depth then holds a surface's distance to about 1e-7 of
/// it at any distance (not reversed, to 6e-8 times distance / near, 1.5e-5 of the far plane's
/// distance half-way there), for the compact layout to rebuild positions from.
pub(crate) fn reversed_depth(view_proj: Mat4) -> Mat4 {
    let reverse = Mat4::from_cols(Vec4::X, Vec4::Y, Vec4::NEG_Z, Vec4::new(0.0, 0.0, 1.0, 1.0));
    reverse * view_proj
}

/// The inverse of [`reversed_depth`]`(view_proj)` to world positions relative to `origin` (clip
/// -> world - origin), the depth a raster pass wrote decoded: the view's translation is not
/// multiplied into terms that cancel, so that f32 rounding moves a rebuilt position along its ray
/// only (inverted in f64 from the very f32 matrix the pass drew with).
pub(crate) fn relative_inverse(view_proj: Mat4, origin: Vec3) -> Mat4 {
    let drawn = reversed_depth(view_proj).as_dmat4();
    (drawn * DMat4::from_translation(origin.as_dvec3()))
        .inverse()
        .as_mat4()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Cone, Intensity};

    fn light(kind: LightKind) -> Light {
        Light {
            kind,
            intensity: Intensity::Native(Vec3::ONE),
        }
    }

    #[test]
    fn a_point_light_s_six_faces_see_every_direction_once() {
        let bounds = (Vec3::ZERO, Vec3::ONE);
        let views = LightView::of_light(
            &light(LightKind::Point {
                position: Vec3::splat(0.5),
            }),
            bounds,
        );
        assert_eq!(views.len(), 6);
        // a direction falls in exactly one face's frustum (away from the faces' edges)
        for d in [
            Vec3::new(0.3, 0.9, -0.2),
            Vec3::new(-0.8, 0.1, 0.5),
            Vec3::new(0.1, -0.2, -0.95),
        ] {
            let inside = views
                .iter()
                .filter(|v| {
                    let c = v.view_proj * (Vec3::splat(0.5) + 0.3 * d).extend(1.0);
                    c.w > 0.0 && c.x.abs() < c.w && c.y.abs() < c.w
                })
                .count();
            assert_eq!(inside, 1, "{d}");
        }
    }

    #[test]
    fn a_directional_light_s_map_holds_the_whole_scene_in_front_of_its_near_plane() {
        let bounds = (Vec3::new(-2.0, 0.0, -1.0), Vec3::new(3.0, 2.0, 4.0));
        let [view] = LightView::of_light(
            &light(LightKind::Directional {
                direction: Vec3::new(-0.3, -1.0, 0.4),
            }),
            bounds,
        )[..] else {
            panic!("one view");
        };
        for i in 0..8 {
            let pick = |bit: usize, a: f32, b: f32| if i & bit == 0 { a } else { b };
            let (lo, hi) = bounds;
            let corner = Vec3::new(
                pick(1, lo.x, hi.x),
                pick(2, lo.y, hi.y),
                pick(4, lo.z, hi.z),
            );
            let c = view.view_proj * corner.extend(1.0);
            assert!(c.x.abs() < 1.0 && c.y.abs() < 1.0, "{corner}: {c}");
            assert!(c.z > 0.0 && c.z < 1.0, "{corner}: depth {}", c.z);
        }
    }

    /// The sun's shadow view, fitted to a camera that sees a corner of a wide floor, is narrower
    /// than its RSM's over the whole floor, and still holds every floor point the camera sees.
    #[test]
    fn the_sun_s_shadow_map_is_fitted_to_what_the_camera_sees() {
        let bounds = (Vec3::new(-20.0, 0.0, -20.0), Vec3::new(20.0, 1.0, 20.0));
        let sun = light(LightKind::Directional {
            direction: Vec3::new(-0.3, -1.0, 0.2),
        });
        let [rsm] = LightView::of_light(&sun, bounds)[..] else {
            panic!("one view");
        };
        let eye = Vec3::new(5.0, 2.0, 5.0);
        let camera = Mat4::perspective_rh(1.0, 1.5, 0.1, 80.0)
            * Mat4::look_at_rh(eye, Vec3::new(20.0, 0.0, 20.0), Vec3::Y);
        let fitted = rsm.shadow_view(camera, bounds, 1024);
        let width = |v: &LightView| match v.projection {
            Projection::Orthographic { width } => width,
            Projection::Perspective { .. } => panic!("orthographic"),
        };
        assert!(
            width(&fitted) < 0.5 * width(&rsm),
            "{} of {}",
            width(&fitted),
            width(&rsm)
        );
        let mut seen = 0;
        for i in 0..=40 {
            for j in 0..=40 {
                let p = Vec3::new(-20.0 + i as f32, 0.0, -20.0 + j as f32);
                let c = camera * p.extend(1.0);
                if !(c.w > 0.0 && c.x.abs() < c.w && c.y.abs() < c.w && c.z < c.w) {
                    continue;
                }
                seen += 1;
                let s = fitted.view_proj * p.extend(1.0);
                assert!(
                    s.x.abs() < 1.0 && s.y.abs() < 1.0 && s.z > 0.0 && s.z < 1.0,
                    "{p}: {s}"
                );
            }
        }
        assert!(seen > 20, "{seen} points seen");
        // a point light's face's shadow view is its RSM's
        let face = LightView::of_light(&light(LightKind::Point { position: Vec3::Y }), bounds)[0];
        assert_eq!(face.shadow_view(camera, bounds, 1024), face);
    }

    #[test]
    fn a_spot_is_one_view_of_twice_its_cone() {
        let cone = Cone {
            direction: Vec3::NEG_Y,
            cone_deg: 40.0,
            falloff_deg: 10.0,
        };
        let views = LightView::of_light(
            &light(LightKind::Spot {
                position: Vec3::new(0.5, 1.0, 0.5),
                cone,
            }),
            (Vec3::ZERO, Vec3::ONE),
        );
        assert_eq!(views.len(), 1);
        assert_eq!(
            views[0].projection,
            Projection::Perspective { fov_deg: 80.0 }
        );
        assert_eq!(views[0].cone, Some((40.0, 10.0)));
    }
}
