//! The main world's lights: Bevy's directional, point and spot lights marked
//! [`IndirectLightSource`] as quadray's, gathered each frame into [`IndirectLightScene`].

use super::cpu_time::CpuTimes;
use super::scene::{IndirectLight, IndirectLightScene, IndirectLightSource};
use bevy::prelude::*;
use quadray_indirect::Scene;
use quadray_indirect::scene::{Cone, Intensity, Light, LightKind};

/// A Bevy colour times a strength, as a light's RGB intensity.
fn coloured(color: Color, strength: f32) -> Intensity {
    let c = LinearRgba::from(color);
    Intensity::Native(Vec3::new(c.red, c.green, c.blue) * strength)
}

/// Bevy's directional light as quadray's: its illuminance along the transform's forward.
pub fn quadray_directional(light: &DirectionalLight, transform: &GlobalTransform) -> Light {
    Light {
        kind: LightKind::Directional {
            direction: transform.forward().as_vec3(),
        },
        intensity: coloured(light.color, light.illuminance),
    }
}

/// Bevy's point light as quadray's: luminous intensity (lumens over 4 pi, as Bevy lights it).
pub fn quadray_point(light: &PointLight, transform: &GlobalTransform) -> Light {
    Light {
        kind: LightKind::Point {
            position: transform.translation(),
        },
        intensity: coloured(light.color, light.intensity / (4.0 * std::f32::consts::PI)),
    }
}

/// Bevy's spot light as quadray's: luminous intensity (lumens over 4 pi, as Bevy lights a spot)
/// on the axis, the outer angle as the cone, the fade from the inner angle as its falloff.
pub fn quadray_spot(light: &SpotLight, transform: &GlobalTransform) -> Light {
    let cone_deg = light.outer_angle.to_degrees();
    Light {
        kind: LightKind::Spot {
            position: transform.translation(),
            cone: Cone {
                direction: transform.forward().as_vec3(),
                cone_deg,
                falloff_deg: (light.outer_angle - light.inner_angle)
                    .to_degrees()
                    .clamp(0.0, cone_deg),
            },
        },
        intensity: coloured(light.color, light.intensity / (4.0 * std::f32::consts::PI)),
    }
}

/// The marked lights of one kind, by entity.
type Marked<'w, 's, L> =
    Query<'w, 's, (Entity, &'static L, &'static GlobalTransform), With<IndirectLightSource>>;

pub(super) fn collect_lights(
    directional: Marked<DirectionalLight>,
    spots: Marked<SpotLight>,
    points: Marked<PointLight>,
    cameras: Query<(), With<IndirectLight>>,
    mut scene: ResMut<IndirectLightScene>,
    mut warned: Local<Option<String>>,
    times: Res<CpuTimes>,
) {
    let _span = times.main();
    let mut warn = |message: String| {
        if warned.as_ref() != Some(&message) {
            warn!("{message}");
            *warned = Some(message);
        }
    };
    fn sorted<L: Component>(
        q: &Marked<L>,
        convert: fn(&L, &GlobalTransform) -> Light,
    ) -> Vec<(Entity, Light)> {
        let mut lights: Vec<_> = q.iter().map(|(e, l, t)| (e, convert(l, t))).collect();
        lights.sort_by_key(|(e, _)| *e);
        lights
    }
    let marked = [
        sorted(&directional, quadray_directional),
        sorted(&spots, quadray_spot),
        sorted(&points, quadray_point),
    ]
    .concat();
    if marked.is_empty() && !cameras.is_empty() {
        warn(
            "quadray indirect light: no light has IndirectLightSource; add that component to \
             the DirectionalLight, PointLight or SpotLight whose bounce the IndirectLight cameras \
             should show"
                .into(),
        );
    }
    let mut lights = Vec::new();
    for (entity, light) in marked {
        let max = Scene::MAX_CONE_DEG;
        let checked = light.validate().and_then(|()| match light.kind {
            LightKind::Spot { cone, .. } if cone.cone_deg > max => Err(format!(
                "its outer angle {:.1} degrees is over {max} (the RSM sees twice the cone)",
                cone.cone_deg
            )),
            _ => Ok(()),
        });
        match checked {
            Ok(()) => lights.push(light),
            Err(e) => warn(format!(
                "quadray indirect light: the IndirectLightSource {} {entity} is skipped: {e}",
                light.kind_name()
            )),
        }
    }
    if scene.lights != lights {
        scene.lights = lights;
    }
}
