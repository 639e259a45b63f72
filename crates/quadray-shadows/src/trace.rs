//! Whitted ray tracing on the grid: eye rays through a pinhole, Blinn-Phong at every reflection
//! point for several point lights, mirror reflection and refraction to a depth, supersampling,
//! rayon over image tiles (deterministic: every pixel depends only on its own rays).

use crate::decide::{Arrival, Decision, Hybrid, Scratch, ShadowRays, ShadowTest, Volumes};
use crate::grid::{CellRecord, Mailbox};
use crate::occlusion::Occluder;
use crate::prepare::{Prepared, Scheme};
use crate::scene::MAX_LIGHTS;
use crate::settings::Settings;
use crate::shadow::LightState;
use crate::stats::RenderStats;
use glam::Vec3;
use quadray_core::geom::Ray;
use quadray_core::image_out::Rgba8Image;
use rayon::prelude::*;
use std::time::Instant;

const TILE: u32 = 16;

/// One render: the user's settings and the shadow test they resolve to.
#[derive(Clone, Copy, Debug)]
pub struct Job {
    /// Size, samples, depth and `check` (the scheme and N_th as resolved in `scheme`).
    pub settings: Settings,
    /// How shadows are decided: `settings.scheme` with its N_th known (`Nth::Auto` predicted).
    pub scheme: Scheme,
    /// Also time HST's shadow-volume decisions and shadow rays one by one (the pilot render of
    /// the N_th prediction does; two clock reads per decision are not free). Not a setting: a
    /// user's render never times them.
    pub time_decisions: bool,
}

/// Eye rays of a pinhole camera for an image of `w` x `h` pixels.
pub struct Pinhole {
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    /// Half the image plane's size at distance 1.
    half: glam::Vec2,
    size: glam::Vec2,
}

impl Pinhole {
    /// The eye rays of `cam` for a `w` x `h` image.
    pub fn new(cam: &crate::scene::Camera, w: u32, h: u32) -> Self {
        let forward = (cam.target - cam.position).normalize();
        let right = forward.cross(cam.up).normalize();
        let half = (cam.fov_y_deg.to_radians() * 0.5).tan();
        Self {
            forward,
            right,
            up: right.cross(forward),
            half: glam::Vec2::new(half * w as f32 / h as f32, half),
            size: glam::Vec2::new(w as f32, h as f32),
        }
    }

    /// Unit direction through the image point `(x, y)` in pixels from the top-left corner.
    pub fn dir(&self, x: f32, y: f32) -> Vec3 {
        let px = (2.0 * x / self.size.x - 1.0) * self.half.x;
        let py = (1.0 - 2.0 * y / self.size.y) * self.half.y;
        (self.forward + self.right * px + self.up * py).normalize()
    }
}

type States = [LightState; MAX_LIGHTS];

struct Tracer<'a, S> {
    prep: &'a Prepared,
    job: Job,
    test: S,
}

/// A rectangle of the image, in pixels from the top-left corner.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Region {
    /// Left column.
    pub x: u32,
    /// Top row.
    pub y: u32,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

impl Region {
    /// The whole of a `width` x `height` image.
    pub fn full(width: u32, height: u32) -> Self {
        Self {
            x: 0,
            y: 0,
            width,
            height,
        }
    }
}

/// The linear RGB radiance of a region of the image, row-major, before tone mapping: what a
/// render computes, so that regions rendered apart assemble into exactly the whole render.
#[derive(Clone, Debug, PartialEq)]
pub struct Radiance {
    /// Where the pixels lie in the image.
    pub region: Region,
    /// `region.width * region.height` pixels, top row first.
    pub pixels: Vec<[f32; 3]>,
}

impl Radiance {
    /// The displayed picture: scaled by `exposure`, clamped to [0, 1], gamma 2.2, rounded to 8
    /// bits.
    pub fn to_rgba8(&self, exposure: f32) -> Rgba8Image {
        let pixels = self
            .pixels
            .iter()
            .map(|&p| {
                let c = (Vec3::from_array(p) * exposure)
                    .clamp(Vec3::ZERO, Vec3::ONE)
                    .powf(1.0 / 2.2)
                    * 255.0
                    + 0.5;
                [c.x as u8, c.y as u8, c.z as u8, 255]
            })
            .collect();
        Rgba8Image {
            width: self.region.width,
            height: self.region.height,
            pixels,
        }
    }
}

/// Renders the scene; `on_tile` is called after each finished tile (for a progress bar). The
/// scene must have at most [`MAX_LIGHTS`] lights and the structures `job.scheme` needs must
/// have been prepared.
pub fn render(prep: &Prepared, job: Job, on_tile: &(dyn Fn() + Sync)) -> (Rgba8Image, RenderStats) {
    let size = job.settings.size;
    let full = Region::full(size.width, size.height);
    let (radiance, stats) = render_region(prep, job, full, on_tile);
    (radiance.to_rgba8(1.0), stats)
}

/// [`render`] of the pixels in `region` alone (inside the `job.settings.size` image), as
/// radiance: every pixel depends only on its own rays, so regions rendered apart are bit for bit
/// the same pixels as the whole render.
pub fn render_region(
    prep: &Prepared,
    job: Job,
    region: Region,
    on_tile: &(dyn Fn() + Sync),
) -> (Radiance, RenderStats) {
    let size = job.settings.size;
    assert!(
        region.x + region.width <= size.width && region.y + region.height <= size.height,
        "region {region:?} outside the {size} image",
    );
    assert!(
        prep.scene.lights.len() <= MAX_LIGHTS,
        "at most {MAX_LIGHTS} lights"
    );
    let volumes = || prep.volumes.as_ref().expect("shadow volumes prepared");
    let grid_rays = || ShadowRays(prep.grid_occluder());
    match job.scheme {
        Scheme::Conventional => render_with(prep, job, region, grid_rays(), on_tile),
        Scheme::Bvh => {
            let bvh = prep.bvh_occluder().expect("BVH prepared");
            render_with(prep, job, region, ShadowRays(bvh), on_tile)
        }
        #[cfg(feature = "embree")]
        Scheme::Embree => {
            let embree = prep.embree.as_ref().expect("Embree scene prepared");
            render_with(prep, job, region, ShadowRays(embree), on_tile)
        }
        #[cfg(not(feature = "embree"))]
        Scheme::Embree => render_with(prep, job, region, grid_rays(), on_tile),
        Scheme::Volume => render_with(prep, job, region, Volumes(volumes()), on_tile),
        Scheme::Hst { nth } => {
            let test = Hybrid {
                volumes: volumes(),
                rays: prep.grid_occluder(),
                nth,
                time_decisions: job.time_decisions,
            };
            render_with(prep, job, region, test, on_tile)
        }
    }
}

/// [`render_region`] with the shadow test chosen.
fn render_with<S: ShadowTest>(
    prep: &Prepared,
    job: Job,
    region: Region,
    test: S,
    on_tile: &(dyn Fn() + Sync),
) -> (Radiance, RenderStats) {
    let tracer = Tracer { prep, job, test };
    let tiles: Vec<Region> = (0..region.height.div_ceil(TILE))
        .flat_map(|ty| {
            (0..region.width.div_ceil(TILE)).map(move |tx| Region {
                x: region.x + tx * TILE,
                y: region.y + ty * TILE,
                width: (region.width - tx * TILE).min(TILE),
                height: (region.height - ty * TILE).min(TILE),
            })
        })
        .collect();
    let start = Instant::now();
    let cpu_start = crate::process_cpu_s();
    let done: Vec<(Vec<[f32; 3]>, RenderStats)> = tiles
        .par_iter()
        .map(|&tile| {
            let out = tracer.tile(tile);
            on_tile();
            out
        })
        .collect();
    let mut stats = RenderStats {
        render_wall_s: start.elapsed().as_secs_f64(),
        render_cpu_s: crate::process_cpu_s() - cpu_start,
        ..Default::default()
    };
    let mut radiance = Radiance {
        region,
        pixels: vec![[0.0; 3]; (region.width * region.height) as usize],
    };
    for (tile, (pixels, s)) in tiles.iter().zip(&done) {
        stats.add(s);
        for (i, p) in pixels.iter().enumerate() {
            let x = tile.x - region.x + i as u32 % tile.width;
            let y = tile.y - region.y + i as u32 / tile.width;
            radiance.pixels[(y * region.width + x) as usize] = *p;
        }
    }
    (radiance, stats)
}

impl<S: ShadowTest> Tracer<'_, S> {
    fn tile(&self, tile: Region) -> (Vec<[f32; 3]>, RenderStats) {
        let start = crate::ticks();
        let prep = self.prep;
        let settings = &self.job.settings;
        let (w, h) = (settings.size.width, settings.size.height);
        let mut scratch = Scratch {
            objects: Mailbox::new(prep.polygons.len()),
            rays: self.test.rays(),
            shadows: Mailbox::new(prep.volumes.as_ref().map_or(0, |v| v.max_per_light())),
            check: Mailbox::new(prep.polygons.len()),
            occupied: CellRecord::new(&prep.grid),
            stats: RenderStats::default(),
        };
        let cam = &prep.scene.camera;
        let pinhole = Pinhole::new(cam, w, h);
        let mut eye_states = [LightState::default(); MAX_LIGHTS];
        if let Some(v) = &prep.volumes {
            for (s, lv) in eye_states.iter_mut().zip(&v.lights) {
                *s = LightState::at_eye(lv.eye_depth);
            }
        }
        let spp = settings.spp.max(1);
        let mut pixels = Vec::new();
        for y in tile.y..tile.y + tile.height {
            for x in tile.x..tile.x + tile.width {
                let mut sum = Vec3::ZERO;
                for s in 0..spp {
                    // A fixed rotated-grid pattern: deterministic antialiasing.
                    let (u, v) = if spp == 1 {
                        (0.5, 0.5)
                    } else {
                        (
                            (s as f32 + 0.5) / spp as f32,
                            ((s as f32 + 0.5) * 0.618_034).fract(),
                        )
                    };
                    let d = pinhole.dir(x as f32 + u, y as f32 + v);
                    sum += self.trace(
                        &mut scratch,
                        cam.position,
                        d,
                        None,
                        settings.depth,
                        eye_states,
                    );
                }
                pixels.push((sum / spp as f32).to_array());
            }
        }
        scratch.stats.tile_ticks = crate::ticks().wrapping_sub(start);
        (pixels, scratch.stats)
    }

    fn trace(
        &self,
        sc: &mut Scratch<S::Rays>,
        o: Vec3,
        d: Vec3,
        skip: Option<u32>,
        depth: u32,
        mut states: States,
    ) -> Vec3 {
        let prep = self.prep;
        sc.occupied.clear();
        let Some(hit) = prep.grid_occluder().closest_hit(
            &Ray::new(o, d, prep.eps, f32::INFINITY),
            skip,
            &mut sc.objects,
            prep.volumes
                .as_ref()
                .map(|v| (v.occupied_cells(), &mut sc.occupied)),
        ) else {
            return prep.scene.background;
        };
        let poly = &prep.polygons[hit.polygon as usize];
        let p = o + d * hit.t;
        // The side the ray arrived on: shading and self-shadowing use this normal.
        let n = if poly.normal.dot(d) < 0.0 {
            poly.normal
        } else {
            -poly.normal
        };
        let mat = prep.scene.materials[prep.scene.faces[hit.polygon as usize].material as usize];
        sc.stats.shading_points += 1;

        let lights = &prep.scene.lights;
        let shadow_start = crate::ticks();
        // Whether a reflected or refracted ray leaves this point and carries the shadow state on.
        let continues = depth > 0 && (mat.reflect > 0.0 || mat.transmit > 0.0);
        let shadowed = self.shadow_conditions(
            sc,
            &mut states,
            Arrival {
                segment: Ray::new(o, d, 0.0, hit.t),
                p,
                n,
                polygon: hit.polygon,
            },
            continues,
        );
        sc.stats.shadow_ticks += crate::ticks().wrapping_sub(shadow_start);
        sc.stats.shadow_decisions += lights.len() as u64;
        if self.job.settings.check {
            let mut differs = 0;
            for (l, light) in lights.iter().enumerate() {
                let to_light = light.position - p;
                let truth = to_light.dot(n) <= 0.0
                    || prep.grid_occluder().occluded(
                        &Ray::segment(p, to_light, prep.shadow_eps),
                        Some(hit.polygon),
                        &mut sc.check,
                    );
                differs += (truth != shadowed[l]) as u64;
            }
            sc.stats.disagreeing_decisions += differs;
            sc.stats.disagreements += (differs > 0) as u64;
        }

        let mut colour = prep.scene.ambient * mat.diffuse;
        for (_, light) in lights.iter().enumerate().filter(|(l, _)| !shadowed[*l]) {
            let ldir = (light.position - p).normalize();
            let half = (ldir - d).normalize();
            colour += light.intensity
                * (mat.diffuse * n.dot(ldir).max(0.0)
                    + Vec3::splat(mat.specular * n.dot(half).max(0.0).powf(mat.shininess)));
        }
        if depth == 0 {
            return colour;
        }
        let mut reflect = mat.reflect;
        if mat.transmit > 0.0 {
            // Entering when the ray meets the outside (the side the normal points to).
            let eta = if poly.normal.dot(d) < 0.0 {
                1.0 / mat.ior
            } else {
                mat.ior
            };
            let cos_i = -n.dot(d);
            let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
            if k < 0.0 {
                reflect += mat.transmit; // total internal reflection
            } else {
                let t = (d * eta + n * (eta * cos_i - k.sqrt())).normalize();
                let mut through = states;
                for (l, light) in lights.iter().enumerate() {
                    // Passing to the far side of the polygon from the light's side, or back.
                    through[l].transmit((light.position - p).dot(n) > 0.0);
                }
                colour +=
                    mat.transmit * self.trace(sc, p, t, Some(hit.polygon), depth - 1, through);
            }
        }
        if reflect > 0.0 {
            let r = d - n * (2.0 * n.dot(d));
            colour += reflect * self.trace(sc, p, r, Some(hit.polygon), depth - 1, states);
        }
        colour
    }

    /// Every light's shadow condition at a shading point. Kept out of line so that profilers
    /// (callgrind's inclusive counts) see the whole of shadow testing as one function.
    #[inline(never)]
    fn shadow_conditions(
        &self,
        sc: &mut Scratch<S::Rays>,
        states: &mut States,
        at: Arrival,
        continues: bool,
    ) -> [bool; MAX_LIGHTS] {
        let prep = self.prep;
        let mut shadowed = [true; MAX_LIGHTS];
        let ns = match &prep.volumes {
            Some(v) => v.counts(sc.occupied.cells()),
            None => [0; MAX_LIGHTS],
        };
        for (l, light) in prep.scene.lights.iter().enumerate() {
            let to_light = light.position - at.p;
            let decision = Decision {
                light: l,
                ns: ns[l],
                to_light,
                self_shadow: to_light.dot(at.n) <= 0.0,
                continues,
            };
            shadowed[l] = self
                .test
                .shadowed(sc, decision, &mut states[l], &at, prep.shadow_eps);
        }
        shadowed
    }
}
