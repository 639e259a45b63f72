//! Today's production baseline: shadow rays as Intel Embree 3 occlusion queries (Debian's
//! libembree-dev; `scripts/setup.sh --embree` installs it). Built only with the `embree` feature.

use crate::occlusion::Occluder;
use embree::sys;
use glam::Vec3;
use quadray_core::geom::{ConvexPolygon, Ray};

/// A committed Embree scene of the polygons, fanned into triangles.
pub struct EmbreeScene {
    device: sys::RTCDevice,
    scene: sys::RTCScene,
    /// Where a ray leaving a polygon starts: Embree cannot skip the polygon a ray starts on.
    leave_eps: f32,
}

// SAFETY: a committed Embree scene may be queried from any number of threads at once, and the
// handles are released only in `drop`.
unsafe impl Send for EmbreeScene {}
unsafe impl Sync for EmbreeScene {}

impl EmbreeScene {
    /// Commits the polygons (degenerate ones left out); rays leaving a polygon start at
    /// `leave_eps`.
    pub fn build(polygons: &[ConvexPolygon], leave_eps: f32) -> Self {
        let triangles: Vec<[Vec3; 3]> = polygons
            .iter()
            .filter(|p| !p.is_degenerate())
            .flat_map(|p| {
                (1..p.vertices.len() - 1)
                    .map(move |i| [p.vertices[0], p.vertices[i], p.vertices[i + 1]])
            })
            .collect();
        // SAFETY: the buffers Embree allocates hold exactly the items written below.
        unsafe {
            let device = sys::rtcNewDevice(std::ptr::null());
            let scene = sys::rtcNewScene(device);
            let geometry = sys::rtcNewGeometry(device, sys::RTCGeometryType::TRIANGLE);
            let count = triangles.len();
            let vertices = sys::rtcSetNewGeometryBuffer(
                geometry,
                sys::RTCBufferType::VERTEX,
                0,
                sys::RTCFormat::FLOAT3,
                12,
                3 * count,
            ) as *mut f32;
            let indices = sys::rtcSetNewGeometryBuffer(
                geometry,
                sys::RTCBufferType::INDEX,
                0,
                sys::RTCFormat::UINT3,
                12,
                count,
            ) as *mut u32;
            for (t, tri) in triangles.iter().enumerate() {
                for (k, v) in tri.iter().enumerate() {
                    let i = 3 * t + k;
                    for a in 0..3 {
                        *vertices.add(3 * i + a) = v[a];
                    }
                    *indices.add(i) = i as u32;
                }
            }
            sys::rtcCommitGeometry(geometry);
            sys::rtcAttachGeometry(scene, geometry);
            sys::rtcReleaseGeometry(geometry);
            sys::rtcCommitScene(scene);
            Self {
                device,
                scene,
                leave_eps,
            }
        }
    }

    /// Is anything hit on the ray?
    pub fn occluded(&self, ray: &Ray) -> bool {
        let (o, d, t_min, t_max) = (ray.origin, ray.dir, ray.t_min, ray.t_max);
        let mut context = sys::RTCIntersectContext {
            flags: sys::RTCIntersectContextFlags::INCOHERENT,
            filter: None,
            instID: [u32::MAX; 1],
        };
        let mut ray = sys::RTCRay {
            org_x: o.x,
            org_y: o.y,
            org_z: o.z,
            tnear: t_min,
            dir_x: d.x,
            dir_y: d.y,
            dir_z: d.z,
            time: 0.0,
            tfar: t_max,
            mask: u32::MAX,
            id: 0,
            flags: 0,
        };
        // SAFETY: the scene is committed; context and ray are valid for the call.
        unsafe { sys::rtcOccluded1(self.scene, &mut context, &mut ray) };
        ray.tfar == f32::NEG_INFINITY
    }
}

impl Occluder for EmbreeScene {
    type Scratch = ();

    fn scratch(&self) {}

    /// A ray leaving polygon `skip` starts at the scene's `leave_eps` at least.
    #[inline]
    fn occluded(&self, ray: &Ray, skip: Option<u32>, _: &mut ()) -> bool {
        match skip {
            Some(_) => self.occluded(&Ray {
                t_min: ray.t_min.max(self.leave_eps),
                ..*ray
            }),
            None => self.occluded(ray),
        }
    }
}

impl Drop for EmbreeScene {
    fn drop(&mut self) {
        // SAFETY: both handles were created in `build` and are released once.
        unsafe {
            sys::rtcReleaseScene(self.scene);
            sys::rtcReleaseDevice(self.device);
        }
    }
}
