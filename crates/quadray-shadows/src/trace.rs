//! Whitted ray tracing on the grid: eye rays through a pinhole, Blinn-Phong at every reflection
//! point for several point lights, mirror reflection and refraction to a depth, supersampling,
//! rayon over image tiles (deterministic: every pixel depends only on its own rays).

use crate::bvh::Bvh;
use crate::geom::{Aabb, ConvexPolygon};
use crate::grid::{CellLists, CellRecord, Grid, Mailbox};
use crate::scene::Scene;
use crate::shadow::{LightState, ShadowVolumes, Subscheme};
use glam::Vec3;
use quadray_core::image_out::Rgba8Image;
use rayon::prelude::*;
use serde::Serialize;
use std::time::Instant;

/// Most lights a scene may have (the per-ray shadow state is a fixed array).
pub const MAX_LIGHTS: usize = 8;
const TILE: u32 = 16;

/// How shadows are decided.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scheme {
    /// A shadow ray through the grid per light, stopping at the first occluder.
    Conventional,
    /// Depth counts carried along every ray segment.
    Volume,
    /// The hybrid switch with threshold N_th.
    Hst { nth: f32 },
    /// A shadow ray through the SAH BVH.
    Bvh,
    /// A shadow ray as an Embree occlusion query (`embree` feature).
    Embree,
}

impl Scheme {
    pub fn name(&self) -> &'static str {
        match self {
            Scheme::Conventional => "conventional",
            Scheme::Volume => "volume",
            Scheme::Hst { .. } => "hst",
            Scheme::Bvh => "bvh",
            Scheme::Embree => "embree",
        }
    }
}

#[derive(Clone, Copy, Debug)]
pub struct Settings {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub depth: u32,
    pub scheme: Scheme,
    /// Also run the conventional test at every shading point and count disagreements.
    pub check: bool,
    /// Also time HST's shadow-volume decisions and shadow rays one by one (the pilot render of
    /// the N_th prediction does; two clock reads per decision are not free).
    pub time_decisions: bool,
}

/// Everything built before rendering: polygons, grid, shadow polygons, BVH.
pub struct Prepared {
    pub scene: Scene,
    pub polygons: Vec<ConvexPolygon>,
    pub grid: Grid,
    pub cells: CellLists,
    pub volumes: Option<ShadowVolumes>,
    pub bvh: Option<Bvh>,
    #[cfg(feature = "embree")]
    pub embree: Option<crate::embree::EmbreeScene>,
    /// CPU seconds spent building the grid (always) and the shadow polygons or BVH the scheme
    /// needs.
    pub preprocess_s: f64,
    /// Smallest ray parameter counted as a hit of a ray leaving a surface (scaled to the scene).
    pub eps: f32,
    /// Scene statistics of the cost model, computed once on first use.
    stats: std::sync::OnceLock<crate::cost::SceneStats>,
    /// The follow-up statistics of the extended N_th, measured once on first use.
    follow_up: std::sync::OnceLock<crate::cost::FollowUp>,
    /// The same for shadow rays: much smaller, so a polygon that a shadow ray crosses right next to
    /// its start (a concave corner) counts, as it does for the depth count. Depth counts take
    /// every crossing after the segment's start.
    pub shadow_eps: f32,
}

impl Prepared {
    pub fn new(scene: Scene, scheme: Scheme) -> Prepared {
        let start = crate::process_cpu_s();
        let polygons = scene.polygons();
        // The grid holds the eye too, so the eye's depth count describes every eye ray's start.
        let bounds = polygons
            .iter()
            .fold(Aabb::EMPTY, |b, p| b.union(p.bounds()))
            .grow(scene.camera.eye);
        let grid = Grid::for_polygons(bounds, polygons.len());
        let cells = grid.register(polygons.par_iter().map(|p| p.vertices.as_slice()));
        let volumes = matches!(scheme, Scheme::Volume | Scheme::Hst { .. })
            .then(|| ShadowVolumes::build(&scene, &polygons, &grid));
        let bvh = (scheme == Scheme::Bvh).then(|| Bvh::build(&polygons));
        #[cfg(feature = "embree")]
        let embree =
            (scheme == Scheme::Embree).then(|| crate::embree::EmbreeScene::build(&polygons));
        Prepared {
            eps: bounds.extent().length() * 1e-5,
            shadow_eps: bounds.extent().length() * 1e-7,
            scene,
            polygons,
            grid,
            cells,
            volumes,
            bvh,
            #[cfg(feature = "embree")]
            embree,
            preprocess_s: crate::process_cpu_s() - start,
            stats: std::sync::OnceLock::new(),
            follow_up: std::sync::OnceLock::new(),
        }
    }
}

impl Prepared {
    /// The cost model's scene statistics (measured once, so every render of this preparation
    /// predicts the same N_th).
    pub fn stats(&self) -> &crate::cost::SceneStats {
        self.stats.get_or_init(|| crate::cost::scene_stats(self))
    }

    /// The N_th HST uses with `--nth auto`: equation 12 with the measured break-even and the
    /// follow-up cost of a conventional decision ([`crate::cost::FollowUp`]), measured once on
    /// pilot renders of recursion `depth` (without shadow polygons: equation 12 as written).
    pub fn predicted_nth(
        &self,
        costs: &crate::cost::MachineCosts,
        depth: u32,
    ) -> (f64, crate::cost::FollowUp) {
        let stats = self.stats();
        let equation_12 = crate::cost::predicted_nth(costs, stats);
        let follow_up = *self
            .follow_up
            .get_or_init(|| crate::cost::follow_up(self, equation_12, depth));
        (
            crate::cost::extended_nth(costs, stats, &follow_up),
            follow_up,
        )
    }
}

/// Counts and times of one render.
#[derive(Clone, Debug, Default, Serialize)]
pub struct RenderStats {
    pub shading_points: u64,
    /// Shading points times lights.
    pub shadow_decisions: u64,
    /// Shading points where some light's condition differs from the conventional test (--check).
    pub disagreements: u64,
    /// Decisions (point, light) that differ from the conventional test (--check).
    pub disagreeing_decisions: u64,
    pub sustain: u64,
    pub self_shadow: u64,
    pub shadow_volume: u64,
    pub conventional: u64,
    pub shadow_polygon_tests: u64,
    pub shadow_polygon_entries: u64,
    /// HST's conventional decisions made because of the carried state (the count invalid and the
    /// condition shadowed or unknown) where N_s alone would have chosen the shadow volume, and
    /// their N_s summed.
    pub forced_conventional: u64,
    pub forced_ns: u64,
    pub shadow_rays: u64,
    /// Ticks ([`crate::ticks`]) the tiles' threads spent deciding shadows, and in the tiles.
    pub shadow_ticks: u64,
    pub tile_ticks: u64,
    /// With [`Settings::time_decisions`]: HST's shadow-volume decisions (the crossing tests) and
    /// its shadow rays, timed and binned by N_s.
    pub shadow_volume_costs: CostBins,
    pub shadow_ray_costs: CostBins,
    pub render_wall_s: f64,
    /// CPU time of the render, all threads (what the paper's CPU minutes measure; unlike clock
    /// time it is not inflated by other processes on a shared machine).
    pub render_cpu_s: f64,
}

impl RenderStats {
    fn add(&mut self, o: &RenderStats) {
        self.shading_points += o.shading_points;
        self.shadow_decisions += o.shadow_decisions;
        self.disagreements += o.disagreements;
        self.disagreeing_decisions += o.disagreeing_decisions;
        self.sustain += o.sustain;
        self.self_shadow += o.self_shadow;
        self.shadow_volume += o.shadow_volume;
        self.conventional += o.conventional;
        self.shadow_polygon_tests += o.shadow_polygon_tests;
        self.shadow_polygon_entries += o.shadow_polygon_entries;
        self.forced_conventional += o.forced_conventional;
        self.forced_ns += o.forced_ns;
        self.shadow_rays += o.shadow_rays;
        self.shadow_ticks += o.shadow_ticks;
        self.tile_ticks += o.tile_ticks;
        self.shadow_volume_costs.merge(&o.shadow_volume_costs);
        self.shadow_ray_costs.merge(&o.shadow_ray_costs);
    }

    /// CPU time of shadow testing: the render's CPU time split in the threads' proportion.
    pub fn shadow_cpu_s(&self) -> f64 {
        if self.tile_ticks > 0 {
            self.render_cpu_s * self.shadow_ticks as f64 / self.tile_ticks as f64
        } else {
            0.0
        }
    }
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
    pub fn new(cam: &crate::scene::Camera, w: u32, h: u32) -> Self {
        let forward = (cam.look_at - cam.eye).normalize();
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

/// Per-tile scratch: mailboxes and the cells of the current ray segment.
struct Scratch {
    objects: Mailbox,
    shadows: Mailbox,
    /// The ground-truth shadow rays of --check, kept apart so they do not disturb the scheme.
    check: Mailbox,
    /// The cells of the current ray segment that hold shadow polygons.
    occupied: CellRecord,
    stats: RenderStats,
}

type States = [LightState; MAX_LIGHTS];

/// A shading point and how the ray segment reached it: `p = o + t d` on `polygon`, `n` the normal
/// on the side it arrived from.
#[derive(Clone, Copy)]
struct Arrival {
    o: Vec3,
    d: Vec3,
    t: f32,
    p: Vec3,
    n: Vec3,
    polygon: u32,
}

struct Tracer<'a> {
    prep: &'a Prepared,
    settings: Settings,
}

/// Renders the scene; `on_tile` is called after each finished tile (for a progress bar).
pub fn render(
    prep: &Prepared,
    settings: Settings,
    on_tile: &(dyn Fn() + Sync),
) -> (Rgba8Image, RenderStats) {
    assert!(
        prep.scene.lights.len() <= MAX_LIGHTS,
        "at most {MAX_LIGHTS} lights"
    );
    let tracer = Tracer { prep, settings };
    let (w, h) = (settings.width, settings.height);
    let tiles: Vec<(u32, u32)> = (0..h.div_ceil(TILE))
        .flat_map(|ty| (0..w.div_ceil(TILE)).map(move |tx| (tx, ty)))
        .collect();
    let start = Instant::now();
    let cpu_start = crate::process_cpu_s();
    let done: Vec<(Vec<[u8; 4]>, RenderStats)> = tiles
        .par_iter()
        .map(|&(tx, ty)| {
            let out = tracer.tile(tx, ty);
            on_tile();
            out
        })
        .collect();
    let mut stats = RenderStats {
        render_wall_s: start.elapsed().as_secs_f64(),
        render_cpu_s: crate::process_cpu_s() - cpu_start,
        ..Default::default()
    };
    let mut image = Rgba8Image::new(w, h, [0, 0, 0, 255]);
    for (&(tx, ty), (pixels, s)) in tiles.iter().zip(&done) {
        stats.add(s);
        let tw = (w - tx * TILE).min(TILE);
        for (i, p) in pixels.iter().enumerate() {
            let (x, y) = (tx * TILE + i as u32 % tw, ty * TILE + i as u32 / tw);
            image.pixels[(y * w + x) as usize] = *p;
        }
    }
    (image, stats)
}

impl Tracer<'_> {
    fn tile(&self, tx: u32, ty: u32) -> (Vec<[u8; 4]>, RenderStats) {
        let start = crate::ticks();
        let prep = self.prep;
        let (w, h) = (self.settings.width, self.settings.height);
        let mut scratch = Scratch {
            objects: Mailbox::new(prep.polygons.len()),
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
        let spp = self.settings.spp.max(1);
        let mut pixels = Vec::new();
        for y in ty * TILE..((ty + 1) * TILE).min(h) {
            for x in tx * TILE..((tx + 1) * TILE).min(w) {
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
                        cam.eye,
                        d,
                        None,
                        self.settings.depth,
                        eye_states,
                    );
                }
                let c = (sum / spp as f32)
                    .clamp(Vec3::ZERO, Vec3::ONE)
                    .powf(1.0 / 2.2)
                    * 255.0
                    + 0.5;
                pixels.push([c.x as u8, c.y as u8, c.z as u8, 255]);
            }
        }
        scratch.stats.tile_ticks = crate::ticks().wrapping_sub(start);
        (pixels, scratch.stats)
    }

    fn trace(
        &self,
        sc: &mut Scratch,
        o: Vec3,
        d: Vec3,
        skip: Option<u32>,
        depth: u32,
        mut states: States,
    ) -> Vec3 {
        let prep = self.prep;
        sc.occupied.clear();
        let Some(hit) = prep.grid.closest_hit(
            &prep.cells,
            &prep.polygons,
            o,
            d,
            prep.eps,
            f32::INFINITY,
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
                o,
                d,
                t: hit.t,
                p,
                n,
                polygon: hit.polygon,
            },
            continues,
        );
        sc.stats.shadow_ticks += crate::ticks().wrapping_sub(shadow_start);
        sc.stats.shadow_decisions += lights.len() as u64;
        if self.settings.check {
            let mut differs = 0;
            for (l, light) in lights.iter().enumerate() {
                let to_light = light.position - p;
                let truth = to_light.dot(n) <= 0.0
                    || occluded_grid(prep, &mut sc.check, p, to_light, hit.polygon);
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
        sc: &mut Scratch,
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
            let self_shadow = to_light.dot(at.n) <= 0.0;
            shadowed[l] = self.shadowed(
                sc,
                l,
                ns[l],
                &mut states[l],
                &at,
                to_light,
                self_shadow,
                continues,
            );
        }
        shadowed
    }

    /// The scheme's shadow condition for light `l` at the shading point, reached through cells
    /// where `ns` shadow polygons of the light are registered.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn shadowed(
        &self,
        sc: &mut Scratch,
        l: usize,
        ns: u32,
        state: &mut LightState,
        at: &Arrival,
        to_light: Vec3,
        self_shadow: bool,
        continues: bool,
    ) -> bool {
        let prep = self.prep;
        let Arrival {
            o,
            d,
            t: t_hit,
            p,
            polygon,
            ..
        } = *at;
        match self.settings.scheme {
            Scheme::Conventional | Scheme::Bvh | Scheme::Embree => {
                sc.stats.conventional += 1;
                if self_shadow {
                    return true;
                }
                sc.stats.shadow_rays += 1;
                self.shadow_ray_with(sc, p, to_light, polygon)
            }
            Scheme::Volume => {
                let v = prep.volumes.as_ref().expect("volumes built");
                sc.stats.shadow_volume += 1;
                sc.stats.shadow_polygon_entries += ns as u64;
                let change = v.crossings(
                    l,
                    sc.occupied.cells(),
                    o,
                    d,
                    0.0,
                    t_hit,
                    &mut sc.shadows,
                    &mut sc.stats.shadow_polygon_tests,
                );
                state.volume_step(change, self_shadow)
            }
            Scheme::Hst { nth } => {
                let v = prep.volumes.as_ref().expect("volumes built");
                let Scratch {
                    objects,
                    shadows,
                    occupied,
                    stats,
                    ..
                } = sc;
                let mut rays = 0;
                let time = self.settings.time_decisions;
                let (shadowed, sub) = state.hst_step(
                    ns,
                    nth,
                    self_shadow,
                    continues,
                    || {
                        stats.shadow_polygon_entries += ns as u64;
                        timed(time, ns, &mut stats.shadow_volume_costs, || {
                            v.crossings(
                                l,
                                occupied.cells(),
                                o,
                                d,
                                0.0,
                                t_hit,
                                shadows,
                                &mut stats.shadow_polygon_tests,
                            )
                        })
                    },
                    || {
                        rays += 1;
                        timed(time, ns, &mut stats.shadow_ray_costs, || {
                            occluded_grid(prep, objects, p, to_light, polygon)
                        })
                    },
                );
                stats.shadow_rays += rays;
                // Tallied without branching on the sub-scheme: it changes from one decision to the
                // next, and a jump on it was mispredicted more often than not.
                stats.sustain += (sub == Subscheme::Sustain) as u64;
                stats.self_shadow += (sub == Subscheme::SelfShadow) as u64;
                stats.shadow_volume += (sub == Subscheme::ShadowVolume) as u64;
                let conventional = (sub == Subscheme::Conventional) as u64;
                stats.conventional += conventional;
                let forced = conventional * (ns > 0 && (ns as f32) <= nth) as u64;
                stats.forced_conventional += forced;
                stats.forced_ns += forced * ns as u64;
                shadowed
            }
        }
    }

    fn shadow_ray_with(&self, sc: &mut Scratch, p: Vec3, to_light: Vec3, polygon: u32) -> bool {
        let prep = self.prep;
        let dist = to_light.length();
        #[cfg(feature = "embree")]
        if let Some(embree) = &prep.embree {
            return embree.occluded(p, to_light / dist, prep.eps, dist);
        }
        match &prep.bvh {
            Some(bvh) => bvh.occluded(
                &prep.polygons,
                p,
                to_light / dist,
                prep.shadow_eps,
                dist,
                Some(polygon),
            ),
            None => occluded_grid(prep, &mut sc.objects, p, to_light, polygon),
        }
    }
}

/// `f()`, timed into `bins` as a decision of N_s `ns` when `on`.
#[inline(always)]
fn timed<R>(on: bool, ns: u32, bins: &mut CostBins, f: impl FnOnce() -> R) -> R {
    if !on {
        return f();
    }
    let start = crate::ticks();
    let r = f();
    bins.add(ns, crate::ticks().wrapping_sub(start));
    r
}

/// Number of [`CostBins`].
pub const COST_BINS: usize = 12;

/// A timed decision that took this many times its bin's median was interrupted (the thread was
/// descheduled or served an interrupt): one such decision of a millisecond would outweigh a
/// thousand real ones in the bin's mean.
const INTERRUPTED: u64 = 16;

/// Timed decisions, read by N_s in bins: bin 0 holds N_s = 0, bin b N_s in `[2^(b-1), 2^b)`,
/// the last all above.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct CostBins {
    /// (N_s, ticks) of each decision.
    samples: Vec<(u32, u64)>,
}

impl CostBins {
    pub fn add(&mut self, ns: u32, ticks: u64) {
        self.samples.push((ns, ticks));
    }

    fn merge(&mut self, o: &CostBins) {
        self.samples.extend_from_slice(&o.samples);
    }

    fn bin(ns: u32) -> usize {
        ((u32::BITS - ns.leading_zeros()) as usize).min(COST_BINS - 1)
    }

    /// Mean N_s and mean ticks of bin `b`'s decisions, if it has at least `min` of them, the
    /// interrupted ones left out.
    pub fn mean(&self, b: usize, min: usize) -> Option<(f64, f64)> {
        let bin: Vec<(u32, u64)> = self
            .samples
            .iter()
            .copied()
            .filter(|&(ns, _)| Self::bin(ns) == b)
            .collect();
        if bin.len() < min.max(1) {
            return None;
        }
        let mut ticks: Vec<u64> = bin.iter().map(|&(_, t)| t).collect();
        let half = ticks.len() / 2;
        let limit = INTERRUPTED * *ticks.select_nth_unstable(half).1;
        let kept: Vec<&(u32, u64)> = bin.iter().filter(|&&(_, t)| t <= limit).collect();
        let n = kept.len() as f64;
        Some((
            kept.iter().map(|&&(ns, _)| ns as f64).sum::<f64>() / n,
            kept.iter().map(|&&(_, t)| t as f64).sum::<f64>() / n,
        ))
    }
}

/// A shadow ray from `p` (on `polygon`) to the light through the grid.
fn occluded_grid(
    prep: &Prepared,
    mailbox: &mut Mailbox,
    p: Vec3,
    to_light: Vec3,
    polygon: u32,
) -> bool {
    let dist = to_light.length();
    prep.grid.occluded(
        &prep.cells,
        &prep.polygons,
        p,
        to_light / dist,
        prep.shadow_eps,
        dist,
        Some(polygon),
        mailbox,
    )
}
