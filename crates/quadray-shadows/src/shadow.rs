//! Shadow volumes in the grid and the hybrid switch (HST) of Eo & Kyung's figure 4.
//!
//! **Depth count.** For light L, a polygon P's shadow volume is every point X whose open segment
//! (L, X) crosses P; the depth count D(X) is the number of polygons whose volume holds X, so X is
//! shadowed exactly when D(X) > 0 (every polygon, transparent or not, blocks a shadow ray, as in the
//! conventional test). Along a ray D changes only where the ray crosses a volume's side (an edge
//! extruded away from L) or a polygon itself. Sides of one edge from its polygons add up: a polygon
//! on the positive side of the extruded plane contributes +1, one on the negative side -1, so the
//! weight of an extruded edge is 0 between two polygons that face L alike and +-2 between two that
//! face it differently, +-1 on a boundary edge: the non-zero ones are exactly Bergeron's silhouette
//! edges. A ray crossing a shadow polygon along its normal changes D by its weight, against it by
//! minus its weight. Ray segments end at every polygon they meet (every hit is a reflection point),
//! so a polygon is only crossed where a ray is refracted through it: D then grows by one going from
//! L's side to the far side and drops by one coming back ([`LightState::transmit`]).
//!
//! **HST.** The four-way switch of the paper's pseudo code, per light and reflection point, with the
//! shadow condition SC and the shadow depth flag SDF carried along the ray. The paper leaves open
//! what a refraction does to them; here a ray refracted through a surface whose far side faces the
//! light starts with an unknown condition (it may have left the shadow), which the next reflection
//! point resolves with a conventional test instead of sustaining it.

use crate::grid::{CellLists, CellSet, Grid, Mailbox};
use crate::scene::{Face, MAX_LIGHTS, Scene};
use glam::{Vec3, Vec4};
use quadray_core::geom::{Aabb, ConvexPolygon, Ray};
use rayon::prelude::*;
use serde::Serialize;

/// A shadow polygon (a silhouette edge `a b` extruded away from the light) prepared for crossing
/// tests: its plane, its edge `a b` and its two sides, the lines from the light through `a` and
/// through `b`. Its far side lies beyond the grid's box, where no ray segment goes, so these
/// three lines decide.
///
/// Which side of a line a ray passes is one triple product of the ray and the line (Pluecker's
/// side relation), so the test needs no crossing point and no division, and it is watertight:
/// neighbouring shadow polygons share the line from the light through their common vertex, and
/// the relation of a ray with that line is computed from the same numbers for both, so exactly
/// one of them counts a ray crossing next to it. Testing each polygon's own crossing point
/// against its own edge planes instead let rounding count such rays twice or not at all on finely
/// meshed models (the bunny's thousands of silhouette edges).
#[derive(Clone, Copy, Debug)]
pub struct ShadowPolygon {
    /// Unit normal and `-normal.p` for points `p` of the plane.
    pub plane: Vec4,
    /// The edge's direction `u` and `(a - light) x u`: the ray's side relation with the edge's
    /// line is `u . m + d . edge_moment` for the ray moment `m = (o - light) x d`.
    edge: [Vec3; 2],
    /// `a - light` and `b - light`: the side relation with the line from the light along `u` is
    /// `u . m`.
    sides: [Vec3; 2],
    /// Signed change of depth count crossing the polygon along its normal.
    pub weight: i32,
}

impl ShadowPolygon {
    /// Change of D along `o + t d`, `t` in `(t0, t1)`: 0 unless the segment crosses the polygon.
    /// `moment` is `(o - light) x d`, the same for every shadow polygon of the light. The three
    /// lines are oriented so that a ray crossing inside has side relations of the sign of its
    /// direction along the normal.
    #[inline]
    pub fn crossing(&self, o: Vec3, d: Vec3, t0: f32, t1: f32, moment: Vec3) -> i32 {
        let n = self.plane.truncate();
        let (s_o, s_d) = (n.dot(o) + self.plane.w, n.dot(d));
        // Both ends on one side of the plane: most tests end here.
        if (s_o + s_d * t0) * (s_o + s_d * t1) >= 0.0 {
            return 0;
        }
        let sides = [
            self.edge[0].dot(moment) + d.dot(self.edge[1]),
            self.sides[0].dot(moment),
            self.sides[1].dot(moment),
        ];
        let inside = if s_d > 0.0 {
            sides.iter().all(|&r| r >= 0.0)
        } else {
            sides.iter().all(|&r| r <= 0.0)
        };
        match (inside, s_d > 0.0) {
            (false, _) => 0,
            (true, true) => self.weight,
            (true, false) => -self.weight,
        }
    }
}

/// The shadow polygons of one light.
pub struct LightVolumes {
    /// The light's position.
    pub light: Vec3,
    /// Its shadow polygons, by the ids registered in the grid.
    pub polygons: Vec<ShadowPolygon>,
    /// D at the eye.
    pub eye_depth: i32,
}

/// Shadow polygons for every light, registered in the grid.
pub struct ShadowVolumes {
    /// Each light's shadow polygons, in the scene's light order.
    pub lights: Vec<LightVolumes>,
    /// Row `cell * lights + light`: that light's shadow polygons registered in the cell. The
    /// lights of one cell are neighbours in memory, so N_s of every light and the polygons of
    /// each come from the same cache lines.
    cells: CellLists,
    /// The cells that hold any light's shadow polygons (most cells a ray crosses hold none).
    occupied: CellSet,
}

impl ShadowVolumes {
    /// Finds the silhouette edges of every light, extrudes them to beyond the grid's box,
    /// registers them in the grid and counts the eye's depth. Every step runs in parallel, and
    /// only silhouette edges (a few percent of a fine mesh's edges) get past the weight.
    pub fn build(scene: &Scene, polygons: &[ConvexPolygon], grid: &Grid) -> Self {
        let eye = scene.camera.position;
        let edges = edge_faces(polygons, &scene.faces);
        let edges: Vec<&[EdgeFace]> = edges.chunk_by(|x, y| x.0 == y.0).collect();
        let (lights, outlines): (Vec<LightVolumes>, Vec<Vec<Outline>>) = scene
            .lights
            .par_iter()
            .map(|l| {
                let light = l.position;
                let (outlines, polys) =
                    silhouette_polygons(polygons, scene, &edges, light, &grid.bounds);
                let volumes = LightVolumes {
                    light,
                    eye_depth: depth_at(polygons, light, eye),
                    polygons: polys,
                };
                (volumes, outlines)
            })
            .unzip();
        let n = lights.len() as u32;
        let all: Vec<(u32, u32, &[Vec3])> = outlines
            .iter()
            .enumerate()
            .flat_map(|(light, o)| {
                o.iter()
                    .enumerate()
                    .map(move |(id, p)| (id as u32, light as u32, p.as_slice()))
            })
            .collect();
        let cells = grid.register_rows(n, all.into_par_iter());
        let mut occupied = CellSet::new(grid.cell_count());
        for c in 0..grid.cell_count() as u32 {
            let rows = cells.row_bounds(c * n, n);
            if rows[n as usize] > rows[0] {
                occupied.insert(c);
            }
        }
        Self {
            lights,
            cells,
            occupied,
        }
    }

    /// Shadow polygons of all lights.
    pub fn polygon_count(&self) -> usize {
        self.lights.iter().map(|l| l.polygons.len()).sum()
    }

    /// The most shadow polygons one light has (the size of a crossing-test mailbox).
    pub fn max_per_light(&self) -> usize {
        self.lights
            .iter()
            .map(|l| l.polygons.len())
            .max()
            .unwrap_or(0)
    }

    /// The cells holding shadow polygons of any light: what a ray walk records
    /// ([`GridOccluder::closest_hit`](crate::occlusion::GridOccluder::closest_hit)) for
    /// [`Self::counts`] and [`Self::crossings`].
    pub fn occupied_cells(&self) -> &CellSet {
        &self.occupied
    }

    /// N_s of every light for a segment whose cells holding shadow polygons are `cells`: the
    /// shadow polygons registered in them (with repeats).
    #[inline]
    pub fn counts(&self, cells: &[u32]) -> [u32; MAX_LIGHTS] {
        let n = self.lights.len() as u32;
        let mut ns = [0u32; MAX_LIGHTS];
        for &c in cells {
            let bounds = self.cells.row_bounds(c * n, n);
            for (acc, w) in ns.iter_mut().zip(bounds.windows(2)) {
                *acc += w[1] - w[0];
            }
        }
        ns
    }

    /// Change of D for `light` along the ray segment, whose cells holding shadow polygons are
    /// `cells`; `tests` counts the ray/shadow-polygon tests.
    #[inline]
    pub fn crossings(
        &self,
        light: usize,
        cells: &[u32],
        ray: &Ray,
        mailbox: &mut Mailbox,
        tests: &mut u64,
    ) -> i32 {
        let (o, d, t0, t1) = (ray.origin, ray.dir, ray.t_min, ray.t_max);
        let (lv, n) = (&self.lights[light], self.lights.len() as u32);
        mailbox.next_ray();
        let moment = (o - lv.light).cross(d);
        let (mut change, mut tested) = (0, 0);
        for &c in cells {
            for &id in self.cells.cell(c * n + light as u32) {
                if mailbox.first_visit(id) {
                    tested += 1;
                    change += lv.polygons[id as usize].crossing(o, d, t0, t1, moment);
                }
            }
        }
        *tests += tested;
        change
    }
}

/// An edge (its vertex indices, the lower first) and a face on it.
type EdgeFace = ((u32, u32), u32);

/// Every (edge, face) pair of the non-degenerate faces, sorted: the faces of one edge are
/// neighbours, in face order.
fn edge_faces(polygons: &[ConvexPolygon], faces: &[Face]) -> Vec<EdgeFace> {
    let mut edges: Vec<EdgeFace> = faces
        .par_iter()
        .enumerate()
        .filter(|(f, _)| !polygons[*f].is_degenerate())
        .flat_map_iter(|(f, face)| {
            let v = &face.vertices;
            (0..v.len()).map(move |i| {
                let (a, b) = (v[i], v[(i + 1) % v.len()]);
                ((a.min(b), a.max(b)), f as u32)
            })
        })
        .collect();
    edges.par_sort_unstable();
    edges
}

/// A shadow polygon's outline: the edge and its far points, for registration in the cells.
type Outline = Vec<Vec3>;

/// Shadow polygons of one light: each silhouette edge extruded away from the light to beyond
/// `bounds`, as outlines (for registration in the cells) and prepared for crossing tests.
fn silhouette_polygons(
    polygons: &[ConvexPolygon],
    scene: &Scene,
    edges: &[&[EdgeFace]],
    light: Vec3,
    bounds: &Aabb,
) -> (Vec<Outline>, Vec<ShadowPolygon>) {
    let corners = (0..8).map(|i| {
        Vec3::new(
            if i & 1 == 0 {
                bounds.min.x
            } else {
                bounds.max.x
            },
            if i & 2 == 0 {
                bounds.min.y
            } else {
                bounds.max.y
            },
            if i & 4 == 0 {
                bounds.min.z
            } else {
                bounds.max.z
            },
        )
    });
    // Far points at 4x the farthest corner: chords between them (at most 90 degrees apart) stay
    // outside the box.
    let reach = 4.0 * corners.map(|c| (c - light).length()).fold(0.0, f32::max);
    let far = |v: Vec3| light + (v - light) * (reach / (v - light).length());
    let vertices = &scene.vertices;
    // How each polygon faces the light: +1 towards, -1 away, 0 edge-on (an empty shadow volume;
    // rounding must not give it a side).
    let facing: Vec<i8> = polygons
        .par_iter()
        .map(|poly| {
            let to_light = light - poly.centroid();
            let f = poly.normal.dot(to_light);
            if poly.is_degenerate() || f.abs() <= 1e-5 * to_light.length() {
                0
            } else if f > 0.0 {
                1
            } else {
                -1
            }
        })
        .collect();
    edges
        .par_iter()
        .filter_map(|faces| {
            let key = faces[0].0;
            // Each polygon on the edge adds +1 when it lies on the positive side of the extruded
            // plane, -1 on the negative side. Which side is decided by how the polygon faces the
            // light and which way it runs along the edge, not by where its centroid falls: for a
            // polygon seen nearly edge-on the two tests round differently, and the bunny's
            // millions of such near-misses left holes in its volumes. Most edges of a fine mesh
            // weigh 0 (not on a silhouette) and end here.
            let weight: i32 = faces
                .iter()
                .map(|&(_, f)| {
                    let v = &scene.faces[f as usize].vertices;
                    let at = v
                        .iter()
                        .position(|&i| i == key.0)
                        .expect("edge of the face");
                    let forward = v[(at + 1) % v.len()] == key.1;
                    let facing = facing[f as usize] as i32;
                    if forward { facing } else { -facing }
                })
                .sum();
            if weight == 0 {
                return None;
            }
            let (a, b) = (vertices[key.0 as usize], vertices[key.1 as usize]);
            if (a - light).length() < 1e-6 || (b - light).length() < 1e-6 {
                return None;
            }
            let (fa, fb) = (far(a), far(b));
            let fm = far((a + b) * 0.5);
            // The plane through the light and the edge, from them alone: the far points, thousands
            // of edge lengths away on a fine mesh, would tilt it by their rounding, and an edge
            // pointing nearly at the light (a sliver of a shadow polygon, but one rays do cross)
            // would read as degenerate and leave a hole in the volume's boundary.
            let n = (b - light).cross(a - light).try_normalize()?;
            // Each line (direction u, moment relative to the light m) oriented so that the ray
            // through a point inside along the normal passes on its positive side.
            let inside = (a + b + fa + fb) * 0.25 - light;
            let ray_moment = inside.cross(n);
            let oriented = |u: Vec3, m: Vec3| {
                let c = u.dot(ray_moment) + n.dot(m);
                (c != 0.0).then_some(if c > 0.0 { [u, m] } else { [-u, -m] })
            };
            let parts = (
                oriented(b - a, (a - light).cross(b - a)),
                oriented(a - light, Vec3::ZERO),
                oriented(b - light, Vec3::ZERO),
            );
            let (Some(edge), Some([side_a, _]), Some([side_b, _])) = parts else {
                return None;
            };
            let polygon = ShadowPolygon {
                plane: n.extend(-n.dot(a)),
                edge,
                sides: [side_a, side_b],
                weight,
            };
            Some((vec![a, b, fb, fm, fa], polygon))
        })
        .unzip()
}

/// D at `p` for `light`: the polygons the open segment (light, p) crosses.
pub fn depth_at(polygons: &[ConvexPolygon], light: Vec3, p: Vec3) -> i32 {
    polygons
        .iter()
        .filter(|poly| poly.intersect(light, p - light, 0.0, 1.0).is_some())
        .count() as i32
}

/// The paper's sub-schemes (table 3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Subscheme {
    /// The condition carried on unchanged.
    Sustain,
    /// The point faces away from the light.
    SelfShadow,
    /// Decided by the depth count.
    ShadowVolume,
    /// Decided by a shadow ray.
    Conventional,
}

/// What a ray carries for one light: the shadow condition SC of where it starts (None: unknown),
/// the shadow depth flag SDF, and the depth count DC (meaningful when SDF is set).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LightState {
    /// SC: shadowed where the ray starts (None: unknown).
    pub sc: Option<bool>,
    /// SDF: the depth count is valid.
    pub sdf: bool,
    /// DC: the depth count.
    pub dc: i32,
}

impl LightState {
    /// The eye's state: its depth count is known.
    pub fn at_eye(depth: i32) -> Self {
        Self {
            sc: Some(depth > 0),
            sdf: true,
            dc: depth,
        }
    }

    /// The pure shadow-volume scheme: D is carried exactly along every segment.
    pub fn volume_step(&mut self, crossings: i32, self_shadow: bool) -> bool {
        self.dc += crossings;
        self.sc = Some(self.dc > 0);
        self.sdf = true;
        self_shadow || self.dc > 0
    }

    /// One step of the paper's pseudo code at a reflection point. `ns` is N_s of the incoming
    /// segment, `crossings` its change of D (only evaluated in the shadow-volume mode), and
    /// `conventional` a shadow ray. `continues` says whether a reflected or refracted ray leaves
    /// the point (so the state carried on is used again). Returns the shadow condition and the
    /// sub-scheme used.
    ///
    /// One departure from the pseudo code: at a self-shadowed point whose depth count is valid, the
    /// count is carried through the point when that is cheap (`ns <= nth`) and a ray continues
    /// from it. The paper drops it there (SDF = 0), and as a self-shadowed point is shadowed
    /// (SC = 1) every later point of the ray then needs a shadow ray until one is lit; on closed
    /// objects half the points face away from each light, so that loss dominated the conventional
    /// share. The count stays exact: a self-shadowed point is reached like any other.
    ///
    /// Always inlined, with the closures it runs: out of line, the crossing test compiled into a
    /// closure of its own and HST's shadow time ran 3-5% above what it is inlined.
    #[inline(always)]
    pub fn hst_step(
        &mut self,
        ns: u32,
        nth: f32,
        self_shadow: bool,
        continues: bool,
        crossings: impl FnOnce() -> i32,
        conventional: impl FnOnce() -> bool,
    ) -> (bool, Subscheme) {
        // Lit means D = 0, so a lit start is a valid count too.
        let count_known = self.sdf || self.sc == Some(false);
        match self.sc {
            Some(sc) if ns == 0 => (sc, Subscheme::Sustain),
            _ if self_shadow => {
                if continues && count_known && (ns as f32) <= nth {
                    self.dc = if self.sdf { self.dc } else { 0 } + crossings();
                    self.sdf = true;
                } else {
                    self.sdf = false;
                }
                self.sc = Some(true);
                (true, Subscheme::SelfShadow)
            }
            Some(_) if (ns as f32) <= nth && count_known => {
                self.dc = if self.sdf { self.dc } else { 0 } + crossings();
                self.sc = Some(self.dc > 0);
                self.sdf = true;
                (self.dc > 0, Subscheme::ShadowVolume)
            }
            _ => {
                let shadowed = conventional();
                self.sc = Some(shadowed);
                self.sdf = false;
                self.dc = 0;
                (shadowed, Subscheme::Conventional)
            }
        }
    }

    /// The state of a ray refracted through the surface: `towards_far_side` when it leaves the
    /// light's side of the polygon (D + 1), false when it comes back to it (D - 1).
    pub fn transmit(&mut self, towards_far_side: bool) {
        let delta = if towards_far_side { 1 } else { -1 };
        let known = self.sdf || self.sc == Some(false);
        if known {
            self.dc = if self.sdf { self.dc } else { 0 } + delta;
            self.sc = Some(self.dc > 0);
            self.sdf = true;
        } else if !(towards_far_side && self.sc == Some(true)) {
            self.sc = None;
        }
    }
}
