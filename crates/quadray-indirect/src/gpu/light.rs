//! The spot light as the passes see it: plain values a renderer fills from its own scene, and
//! the per-light uniforms made from them (the light itself, the gather's per-light terms).

use super::contract::{LightTermsUniform, LightUniform};
use crate::scene::{Scene, SpotLight, extent_of};
use crate::settings::Settings;
use glam::{Mat4, Vec3};

/// A spot light and the projection of its reflective shadow map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spot {
    /// World -> light clip space (a perspective of twice the cone, square): the RSM's projection.
    pub view_proj: Mat4,
    /// Where the light is (world units).
    pub position: Vec3,
    /// Unit axis of the cone.
    pub direction: Vec3,
    /// Half-angle of the cone (degrees); also half the RSM's field of view.
    pub cone_deg: f32,
    /// Full intensity inside `cone_deg - falloff_deg`, fading to zero at `cone_deg`.
    pub falloff_deg: f32,
    /// Radiant intensity on the axis (W/sr per channel).
    pub intensity: [f32; 3],
    /// The scene's size (its bounds' diagonal): the unit of RSM depth, in which the validity
    /// thresholds are given.
    pub extent: f32,
    /// The light's far plane: everything lit is closer.
    pub far: f32,
}

impl Spot {
    /// The light of a quadray [`Scene`].
    pub fn of_scene(scene: &Scene) -> Self {
        Self::new(&scene.light, scene.bounds())
    }

    /// `light` over geometry within `bounds` (min, max): for a renderer that keeps its own
    /// scene (the RSM's projection and depth unit follow the bounds).
    pub fn new(light: &SpotLight, bounds: (Vec3, Vec3)) -> Self {
        Self {
            view_proj: light.view_proj(bounds),
            position: light.position,
            direction: light.spot.direction.normalize(),
            cone_deg: light.spot.cone_deg,
            falloff_deg: light.spot.falloff_deg,
            intensity: light.intensity.to_array(),
            extent: extent_of(bounds),
            far: light.far(bounds),
        }
    }

    /// Side of an RSM texel on the plane at unit distance along the axis.
    pub(crate) fn texel_side(&self, rsm_size: u32) -> f32 {
        2.0 * self.cone_deg.to_radians().tan() / rsm_size as f32
    }

    /// The gather's per-light values for `settings`, with the clamp `r_min` of the VPL kernel's
    /// 1/r^4 (world units).
    pub(crate) fn terms(&self, settings: &Settings, r_min: f32) -> LightTermsUniform {
        let texel_side = self.texel_side(settings.rsm_size);
        LightTermsUniform {
            r_min,
            // a few shadow-map texels' worth of depth at the far side of the scene
            depth_bias: 0.005 + 3.0 * texel_side * self.far / self.extent,
            plane_agreement: 0.02 * self.extent,
            shadow_thickness: settings.shadow_thickness * self.extent,
        }
    }

    pub(crate) fn uniform(&self) -> LightUniform {
        let cone = self.cone_deg.to_radians();
        let (p, d, i) = (self.position, self.direction, self.intensity);
        LightUniform {
            view_proj: self.view_proj.to_cols_array_2d(),
            position: [p.x, p.y, p.z, 1.0 / self.extent],
            direction: [d.x, d.y, d.z, cone.cos()],
            intensity: [
                i[0],
                i[1],
                i[2],
                (cone - self.falloff_deg.to_radians()).cos(),
            ],
        }
    }
}
