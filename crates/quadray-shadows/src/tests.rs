//! Tests against ground truth: brute force over all polygons for the grid and the BVH, the
//! depth count against counting the polygons between a point and the light, and every scheme's
//! shadow condition against the conventional test at every shading point.

use crate::cost::{self, MachineCosts};
use crate::grid::{CellRecord, CellSet, Mailbox};
use crate::occlusion::{GridOccluder, Occluder};
use crate::prepare::{Prepared, Scheme};
use crate::scene::{BUILTINS, Face, Scene};
use crate::shadow::{LightState, ShadowVolumes, depth_at};
use crate::{BuildError, Nth, RunReport, SchemeChoice, Settings, Size};
use glam::Vec3;
use quadray_core::geom::{ConvexPolygon, Ray};
use quadray_core::image_out::Rgba8Image;
use quadray_core::random::SplitMix;
use std::path::Path;

fn brute_closest(polys: &[ConvexPolygon], o: Vec3, d: Vec3, t_min: f32) -> Option<(f32, u32)> {
    polys
        .iter()
        .enumerate()
        .filter_map(|(i, p)| {
            p.intersect(o, d, t_min, f32::INFINITY)
                .map(|t| (t, i as u32))
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
}

/// A builtin scene plus degenerate polygons (collinear, repeated vertices) sharing its vertices.
fn scene_with_degenerates(name: &str) -> Scene {
    let mut s = Scene::builtin(name).unwrap();
    let n = s.vertices.len() as u32;
    let (a, b) = (s.vertices[0], s.vertices[1]);
    s.vertices.push(a + (b - a) * 0.5);
    s.faces.push(Face {
        vertices: vec![0, n, 1],
        material: 0,
    });
    s.faces.push(Face {
        vertices: vec![2, 2, 2],
        material: 0,
    });
    s
}

/// Random rays, and rays lying on cell boundary planes along the grid axes.
fn test_rays(prep: &Prepared, count: usize) -> Vec<(Vec3, Vec3)> {
    let mut rng = SplitMix(11);
    let b = prep.grid.bounds;
    let point = |rng: &mut SplitMix| {
        b.min + b.extent() * Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32())
    };
    let mut rays = Vec::new();
    for i in 0..count {
        let o = point(&mut rng);
        if i % 2 == 0 {
            let d = Vec3::new(
                rng.next_f32() - 0.5,
                rng.next_f32() - 0.5,
                rng.next_f32() - 0.5,
            )
            .normalize();
            rays.push((o, d));
        } else {
            // Snap two coordinates onto cell boundaries, walk along the third axis.
            let axis = i % 3;
            let mut o = o;
            for a in (0..3).filter(|&a| a != axis) {
                let k = ((o[a] - b.min[a]) / prep.grid.cell_size[a]).round();
                o[a] = b.min[a] + k * prep.grid.cell_size[a];
            }
            let mut d = Vec3::ZERO;
            d[axis] = if i % 4 == 1 { 1.0 } else { -1.0 };
            rays.push((o, d));
        }
    }
    rays
}

#[test]
fn builtin_scenes_have_the_papers_polygon_and_light_counts() {
    for (name, polygons, lights) in BUILTINS {
        let s = Scene::builtin(name).unwrap();
        assert_eq!(
            (s.faces.len(), s.lights.len()),
            (polygons, lights),
            "{name}"
        );
        for (i, p) in s.polygons().iter().enumerate() {
            assert!(!p.is_degenerate(), "{name}: face {i} degenerate");
            let size = p.bounds().extent().max_element();
            for v in &p.vertices {
                assert!(
                    (p.normal.dot(*v) - p.offset).abs() < 1e-4 * size,
                    "{name}: face {i} not planar"
                );
            }
        }
    }
}

#[test]
fn grid_closest_hit_equals_brute_force() {
    for name in ["stars", "desk", "kaist"] {
        let prep = Prepared::new(scene_with_degenerates(name), Scheme::Conventional);
        let mut mailbox = Mailbox::new(prep.polygons.len());
        for (o, d) in test_rays(&prep, 4000) {
            let grid = prep.grid_occluder().closest_hit(
                &Ray::new(o, d, 0.0, f32::INFINITY),
                None,
                &mut mailbox,
                None,
            );
            let brute = brute_closest(&prep.polygons, o, d, 0.0);
            match (grid, brute) {
                (None, None) => {}
                (Some(g), Some((t, id))) => assert!(
                    g.polygon == id || (g.t - t).abs() <= 1e-5 * t.max(1.0),
                    "{name}: {g:?} vs {t} {id} for {o} {d}"
                ),
                _ => panic!("{name}: grid {grid:?} vs brute force {brute:?} for ray {o} {d}"),
            }
        }
    }
}

/// Registration against brute force: a polygon is in exactly the cells whose box (padded by
/// 1e-4 of a cell, as registration pads) it meets, found by clipping it to every cell. Random
/// triangles, many reaching far out of the grid as shadow polygons do, in two slots per cell
/// (how every light's shadow polygons are registered at once).
#[test]
fn registration_equals_clipping_to_every_cell() {
    use crate::clip::clip_slab;
    use crate::grid::Grid;
    use quadray_core::geom::Aabb;
    use rayon::prelude::*;
    let bounds = Aabb {
        min: Vec3::new(-1.0, -2.0, 0.5),
        max: Vec3::new(3.0, 1.0, 2.5),
    };
    let grid = Grid::with_resolution(bounds, [7, 5, 4]);
    let mut rng = SplitMix(17);
    let mut point = |reach: f32| {
        let u =
            Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * (2.0 * reach + 1.0) - reach;
        bounds.min + u * bounds.extent()
    };
    let triangles: Vec<Vec<Vec3>> = (0..300)
        .map(|i| {
            let reach = if i % 3 == 0 { 4.0 } else { 0.0 };
            vec![point(0.0), point(reach), point(reach)]
        })
        .collect();
    let lists = grid.register_rows(
        2,
        triangles
            .par_iter()
            .enumerate()
            .map(|(i, t)| (i as u32 / 2, i as u32 % 2, t.as_slice())),
    );
    let pad = grid.cell_size * 1e-4;
    let (mut tmp, mut a, mut b) = (Vec::new(), Vec::new(), Vec::new());
    let mut registrations = 0;
    for (i, t) in triangles.iter().enumerate() {
        let (id, slot) = (i as u32 / 2, i as u32 % 2);
        for c in 0..grid.cell_count() as u32 {
            let cell = [c % 7, c / 7 % 5, c / 35];
            let mut meets = true;
            a.clone_from(t);
            for axis in 0..3 {
                let lo = bounds.min[axis] + cell[axis] as f32 * grid.cell_size[axis];
                let hi = lo + grid.cell_size[axis];
                clip_slab(&a, axis, lo - pad[axis], hi + pad[axis], &mut tmp, &mut b);
                std::mem::swap(&mut a, &mut b);
                meets &= !a.is_empty();
            }
            let registered = lists.cell(c * 2 + slot).contains(&id);
            assert_eq!(registered, meets, "triangle {i} {t:?}, cell {cell:?}");
            registrations += meets as usize;
        }
    }
    assert_eq!(lists.registrations(), registrations);
    assert!(registrations > 1000, "{registrations}");
}

#[test]
fn the_walk_notes_the_cells_of_the_set_it_crosses_even_on_the_longest_walks() {
    // Eye rays, rays along cell boundaries, and the grid's four diagonals from corner to corner
    // (the longest walks there are), through a set of every other cell and one of every cell
    // (where the longest walks fill the record).
    let prep = Prepared::new(scene_with_degenerates("kaist"), Scheme::Conventional);
    let grid = &prep.grid;
    let no_polygons = grid.register(rayon::iter::empty::<&[Vec3]>());
    let (b, e) = (grid.bounds, grid.bounds.extent());
    let mut rays = test_rays(&prep, 1000);
    for corner in 0..4 {
        let flip = Vec3::new((corner & 1) as f32, (corner >> 1) as f32, 0.0);
        let from = b.min + e * flip;
        let to = b.min + e * (Vec3::ONE - flip);
        rays.push((from, (to - from).normalize()));
    }
    let (mut mailbox, mut record) = (Mailbox::new(1), CellRecord::new(grid));
    let longest = grid.res.iter().sum::<u32>() as usize - 2;
    for step in [2, 1] {
        let mut set = CellSet::new(grid.cell_count());
        (0..grid.cell_count() as u32)
            .filter(|c| c % step == 0)
            .for_each(|c| set.insert(c));
        let mut longest_noted = 0;
        for &(o, d) in &rays {
            record.clear();
            let empty = GridOccluder {
                grid,
                cells: &no_polygons,
                polygons: &[],
            };
            let hit = empty.closest_hit(
                &Ray::new(o, d, 0.0, f32::INFINITY),
                None,
                &mut mailbox,
                Some((&set, &mut record)),
            );
            assert!(hit.is_none());
            let mut members = Vec::new();
            grid.walk(&Ray::new(o, d, 0.0, f32::INFINITY), |c, _, _| {
                if c % step == 0 {
                    members.push(c);
                }
                false
            });
            assert_eq!(record.cells(), members, "ray {o} {d}");
            longest_noted = longest_noted.max(members.len());
        }
        if step == 1 {
            assert!(
                longest_noted + 4 >= longest,
                "the diagonals walk {longest_noted} cells of at most {longest}"
            );
        }
    }
}

#[test]
fn bvh_and_grid_occlusion_equal_brute_force() {
    let prep = Prepared::new(scene_with_degenerates("kaist"), Scheme::Bvh);
    let bvh = prep.bvh.as_ref().unwrap();
    let mut mailbox = Mailbox::new(prep.polygons.len());
    for (o, d) in test_rays(&prep, 3000) {
        let t_max = 3.0;
        let brute = prep
            .polygons
            .iter()
            .any(|p| p.intersect(o, d, 0.0, t_max).is_some());
        assert_eq!(
            bvh.occluded(&prep.polygons, &Ray::new(o, d, 0.0, t_max), None),
            brute,
            "bvh {o} {d}"
        );
        assert_eq!(
            prep.grid_occluder()
                .occluded(&Ray::new(o, d, 0.0, t_max), None, &mut mailbox),
            brute,
            "grid {o} {d}"
        );
    }
}

/// D at `p`, unless nudging `p` by a ten-thousandth of the scene changes it.
fn stable_depth(prep: &Prepared, light: Vec3, p: Vec3) -> Option<i32> {
    let nudge = prep.grid.bounds.extent().length() * 1e-4;
    let d = depth_at(&prep.polygons, light, p);
    let same = (0..3).all(|a| {
        let mut e = Vec3::ZERO;
        e[a] = nudge;
        depth_at(&prep.polygons, light, p + e) == d && depth_at(&prep.polygons, light, p - e) == d
    });
    same.then_some(d)
}

/// D(end) = D(start) + the signed shadow-polygon crossings between, on segments that meet no
/// object polygon, for every light (including the desk lamp's light inside the grid), random and
/// along cell boundaries, with degenerate polygons in the scene.
#[test]
fn depth_count_along_segments_equals_polygons_counted_to_the_light() {
    // The desk again with its lamp's light on the lamp's axis: inside the stem and exactly in the
    // planes of the flare's faces (edge-on polygons).
    let mut on_axis = scene_with_degenerates("desk");
    on_axis.lights[0].position = Vec3::new(-1.5, 2.25, -0.3);
    on_axis.name = "desk, light on the lamp's axis".into();
    let scenes = [
        on_axis,
        scene_with_degenerates("desk"),
        scene_with_degenerates("stars"),
        scene_with_degenerates("kaist"),
    ];
    for scene in scenes {
        let name = scene.name.clone();
        let prep = Prepared::new(scene, Scheme::Volume);
        let volumes = prep.volumes.as_ref().unwrap();
        let mut objects = Mailbox::new(prep.polygons.len());
        let mut shadows = Mailbox::new(volumes.max_per_light());
        let (mut occupied, mut tests, mut checked) = (CellRecord::new(&prep.grid), 0, 0);
        for (o, d) in test_rays(&prep, 1500) {
            occupied.clear();
            let t1 = prep
                .grid_occluder()
                .closest_hit(
                    &Ray::new(o, d, 0.0, 2.0),
                    None,
                    &mut objects,
                    Some((volumes.occupied_cells(), &mut occupied)),
                )
                .map_or(2.0, |h| h.t * 0.5);
            let end = o + d * t1;
            if !prep.grid.bounds.grow(end).eq(&prep.grid.bounds) {
                continue;
            }
            for (l, light) in prep.scene.lights.iter().enumerate() {
                // Points within rounding of a polygon have no well-defined count: skip them.
                let (Some(d0), Some(d1)) = (
                    stable_depth(&prep, light.position, o),
                    stable_depth(&prep, light.position, end),
                ) else {
                    continue;
                };
                let change = volumes.crossings(
                    l,
                    occupied.cells(),
                    &Ray::new(o, d, 0.0, t1),
                    &mut shadows,
                    &mut tests,
                );
                assert_eq!(
                    d0 + change,
                    d1,
                    "{name}: light {l}, segment {o} -> {end}, d0 {d0} change {change}"
                );
                checked += 1;
            }
        }
        assert!(checked > 1000, "{name}: only {checked} segments checked");
    }
}

/// Machine constants of the tests: fixed, so that no test waits for a calibration.
const COSTS: MachineCosts = MachineCosts {
    c_s: 5.0,
    c_i: 20.0,
    c_c: 3.0,
    c_o: 5.0,
};

/// [`crate::run`] with [`COSTS`] for the measured constants.
fn run(scene: Scene, settings: &Settings) -> Result<(Rgba8Image, RunReport), BuildError> {
    let prep = crate::prepare(scene, settings.scheme)?;
    Ok(crate::render_prepared(&prep, settings, &COSTS, &|| {}))
}

fn options(scheme: SchemeChoice, nth: Nth) -> Settings {
    Settings {
        scheme,
        nth,
        size: Size::new(96, 72),
        depth: 4,
        check: true,
        ..Settings::DEFAULT
    }
}

/// The bar, at most 1e-4 of the shading points, rounded up to whole points on these small
/// test images (grazing light can still flip a rare point in the pure shadow-volume mode).
fn assert_same_as_conventional(scene: &Scene, what: &str) {
    for (scheme, nth) in [
        (SchemeChoice::Volume, Nth::Auto),
        (SchemeChoice::Hst, Nth::Auto),
        (SchemeChoice::Hst, Nth::Fixed(0.0)),
        (SchemeChoice::Hst, Nth::Fixed(1e9)),
        (SchemeChoice::Bvh, Nth::Auto),
    ] {
        assert_agrees(scene, &options(scheme, nth), 1000, what);
    }
}

/// Renders with `--check` and asserts on more than `min_points` shading points that at most the
/// bar's share disagrees with the conventional test.
fn assert_agrees(scene: &Scene, opts: &Settings, min_points: u64, what: &str) {
    let (_, r) = run(scene.clone(), opts).unwrap();
    let bad = r.disagreements.unwrap();
    let points = r.shading_points;
    assert!(points > min_points, "{what}: {points} shading points");
    assert!(
        bad as f64 <= (1e-4 * points as f64).ceil(),
        "{what} {:?} {:?}: {bad} of {points} shading points disagree",
        opts.scheme,
        opts.nth
    );
}

#[test]
fn volume_hst_and_bvh_decide_like_the_conventional_test_on_every_builtin() {
    for (name, ..) in BUILTINS {
        assert_same_as_conventional(&Scene::builtin(name).unwrap(), name);
    }
}

const GLASS_BOX: &str = r#"
name = "glass box"
[camera]
eye = [0.3, 1.2, 4.0]
look_at = [0.0, 0.8, 0.0]
fov_y_deg = 50
[[lights]]
position = [0.41, 3.03, -0.29]
intensity = [1, 1, 1]
[[lights]]
position = [0.1, 0.9, 0.2]
intensity = [0.5, 0.5, 0.5]
[materials.glass]
diffuse = [0.1, 0.1, 0.1]
transmit = 0.9
reflect = 0.1
ior = 1.3
[materials.floor]
diffuse = [0.8, 0.8, 0.8]
[[objects]]
material = "glass"
box = { min = [-0.5, 0.6, -0.6], max = [0.6, 1.4, 0.5] }
[[objects]]
material = "glass"
box = { min = [-1.4, 0.2, -0.77], max = [-0.9, 0.5, 0.9] }
[[objects]]
material = "floor"
polygons = [
  [[-3, 0, -3], [-3, 0, 3], [3, 0, 3], [3, 0, -3]],
  [[-3, 0, -3], [3, 0, -3], [3, 3, -3], [-3, 3, -3]],
  [[1, 0.5, 0], [1.5, 0.5, 0], [2, 0.5, 0]],
]
"#;

/// Rays refracted through a transparent box, the second light inside the grid (under the box),
/// a degenerate polygon: a depth count that ignores what refraction crosses disagrees here.
#[test]
fn refraction_through_glass_and_a_light_inside_the_grid_keep_the_depth_count() {
    let scene = Scene::parse(GLASS_BOX, Path::new("glass-box.toml")).unwrap();
    assert_same_as_conventional(&scene, "glass box");
}

#[test]
fn transmission_updates_the_carried_state() {
    let mut s = LightState::at_eye(0);
    s.transmit(true);
    assert_eq!((s.sc, s.sdf, s.dc), (Some(true), true, 1));
    s.transmit(false);
    assert_eq!((s.sc, s.dc), (Some(false), 0));
    // Shadowed with an unknown count: coming back to the light's side leaves it unknown.
    let mut u = LightState {
        sc: Some(true),
        sdf: false,
        dc: 0,
    };
    u.transmit(true);
    assert_eq!(u.sc, Some(true));
    u.transmit(false);
    assert_eq!(u.sc, None);
    // An unknown condition is never sustained: the next point takes a shadow ray.
    let decided = u.hst_step(0, 10.0, false, true, || unreachable!(), || false);
    assert_eq!(decided, (false, crate::shadow::Subscheme::Conventional));
}

#[test]
fn renders_are_deterministic_and_not_empty() {
    let opts = Settings {
        check: false,
        ..options(SchemeChoice::Hst, Nth::Fixed(8.0))
    };
    let (a, r) = run(Scene::builtin("stars").unwrap(), &opts).unwrap();
    let (b, _) = run(Scene::builtin("stars").unwrap(), &opts).unwrap();
    assert_eq!(a, b);
    assert!(
        a.pixels
            .iter()
            .collect::<std::collections::HashSet<_>>()
            .len()
            > 50
    );
    let s = &r.subschemes;
    assert_eq!(
        s.sustain + s.self_shadow + s.shadow_volume + s.conventional,
        r.shadow_decisions
    );
}

#[test]
fn cost_model_limits() {
    let c = MachineCosts {
        c_s: 2.00,
        c_i: 2.54,
        c_c: 0.23,
        c_o: 1.88,
    };
    let prep = Prepared::new(Scene::builtin("stars").unwrap(), Scheme::Conventional);
    let mut s = crate::pilot::scene_stats(&prep);
    assert!(s.p > 0.0 && s.p < 1.0 && s.alpha > 0.0 && s.n_c >= 1.0);
    s.n_o = 0.0;
    assert!((cost::conventional_cost(&c, &s) - c.c_i).abs() < 1e-9);
    // The paper's Glasses row (table 2): p 0.276, alpha 0.115 with its table-1 constants gives
    // N_th 7.04 when a shadow ray meets N_o = 6.55 new polygons.
    (s.p, s.alpha, s.n_o) = (0.276, 0.115, 6.55);
    assert!((cost::predicted_nth(&c, &s) - 7.04).abs() < 0.02);
    s.n_o = 1e6;
    let limit = c.c_i + c.c_c / (1.0 - (1.0_f64 - 0.276).powf(0.115)) + c.c_o / 0.276;
    assert!((cost::conventional_cost(&c, &s) - limit).abs() < 1e-6);
}

#[test]
fn break_even_is_where_shadow_volumes_start_to_cost_more_than_rays() {
    use crate::cost::CostBins;
    // 100 decisions each: (N_s, ticks of a shadow-volume decision, of a ray); bins 3 to 6.
    let table = [(5, 50, 300), (10, 200, 300), (20, 400, 300), (40, 900, 300)];
    let bins = |table: &[(u32, u64, usize)]| {
        let mut bins = CostBins::default();
        for &(ns, ticks, n) in table {
            (0..n).for_each(|_| bins.add(ns, ticks));
        }
        bins
    };
    let volume: Vec<_> = table.iter().map(|&(ns, v, _)| (ns, v, 100)).collect();
    let rays: Vec<_> = table.iter().map(|&(ns, _, r)| (ns, r, 100)).collect();
    // Excess -100 at N_s 10 and +100 at 20: they meet half way.
    let even = |v: &[(u32, u64, usize)], r: &[(u32, u64, usize)]| {
        cost::break_even(&bins(v), &bins(r)).unwrap()
    };
    assert!((even(&volume, &rays) - 15.0).abs() < 1e-9);
    // A few interrupted decisions, a thousand times slower, do not move it.
    let mut interrupted = volume.clone();
    interrupted.extend([(5, 50_000, 2), (10, 200_000, 1)]);
    assert!((even(&interrupted, &rays) - 15.0).abs() < 1e-9);
    // Too few decisions in the two middle bins: from 5 (excess -250) to 40 (+600).
    let (mut sparse_volume, mut sparse_rays) = (volume.clone(), rays.clone());
    sparse_volume[1].2 = 10;
    sparse_rays[2].2 = 10;
    let expected = 5.0 + 35.0 * 250.0 / 850.0;
    assert!((even(&sparse_volume, &sparse_rays) - expected).abs() < 1e-9);
    // Cheaper everywhere (of the bins with enough decisions): the top of the last bin timed
    // (N_s 40 lies in [32, 64)).
    sparse_rays[3].1 = 1000;
    assert_eq!(even(&sparse_volume, &sparse_rays), 64.0);
    // Nothing timed.
    assert_eq!(
        cost::break_even(&CostBins::default(), &CostBins::default()),
        None
    );
}

#[test]
fn calibration_measures_positive_constants() {
    let c = cost::calibrate();
    assert!(
        c.c_s > 0.0 && c.c_i > 0.0 && c.c_c > 0.0 && c.c_o > 0.0,
        "{c:?}"
    );
}

#[test]
fn shadow_polygons_are_silhouettes_only() {
    // A closed box under one light: only edges between lit and unlit faces are extruded.
    let s = Scene::parse(GLASS_BOX, Path::new("glass-box.toml")).unwrap();
    let prep = Prepared::new(s, Scheme::Volume);
    let v: &ShadowVolumes = prep.volumes.as_ref().unwrap();
    // Light 0 is above the boxes: each box shows 1 or 2 side faces plus its top: 4-6 silhouette
    // edges each, weight 2; the floor and wall quads add their open boundary edges, weight 1.
    let w: Vec<i32> = v.lights[0].polygons.iter().map(|p| p.weight).collect();
    let doubles = w.iter().filter(|&&x| x.abs() == 2).count();
    assert!(
        (8..=12).contains(&doubles),
        "{doubles} silhouette edges of weight 2"
    );
    assert!(w.iter().all(|&x| x.abs() == 1 || x.abs() == 2));
}

#[test]
fn malformed_scene_files_are_clear_errors() {
    let cases = [
        ("not toml", "expected"),
        (
            &GLASS_BOX.replace("fov_y_deg = 50", "fov_y_deg = 500"),
            "fov_y_deg",
        ),
        (
            &GLASS_BOX.replace("material = \"floor\"", "material = \"wood\""),
            "unknown material",
        ),
        (
            &GLASS_BOX.replace(
                "[1, 0.5, 0], [1.5, 0.5, 0], [2, 0.5, 0]",
                "[0, 0, 0], [1, 0, 0], [1, 1, 0.5], [0, 1, 0]",
            ),
            "not planar",
        ),
        (
            &GLASS_BOX.replace(
                "[1, 0.5, 0], [1.5, 0.5, 0], [2, 0.5, 0]",
                "[0, 0, 0], [2, 0, 0], [1, 0.2, 0], [1, 2, 0]",
            ),
            "not convex",
        ),
        (
            &GLASS_BOX.replace(
                "[1, 0.5, 0], [1.5, 0.5, 0], [2, 0.5, 0]",
                "[0, 0, 0], [1, 0, 0]",
            ),
            "at least 3",
        ),
        (
            &GLASS_BOX.replace(
                "position = [0.41, 3.03, -0.29]",
                "position = [nan, 3.0, -0.3]",
            ),
            "not finite",
        ),
    ];
    for (text, why) in cases {
        let e = Scene::parse(text, Path::new("bad.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("bad.toml: ") && e.contains(why), "{e}");
    }
    assert!(Scene::load(Path::new("/nonexistent/scene.toml")).is_err());
}

/// A scene file from the repository's assets.
fn asset_scene(file: &str) -> Scene {
    Scene::load(&crate::scene::assets_dir().join(file)).unwrap()
}

/// The bunny's 69,451 triangles put thousands of silhouette edges, many of them nearly edge-on
/// or pointing nearly at a light, around three lights inside the room: silhouette weights taken
/// from a centroid's side of the extruded plane, or shadow-polygon sides tested apart for each
/// polygon, left holes in the volumes that the pure shadow-volume scheme carried into whole rows
/// of wrong pixels.
#[test]
fn the_bunny_in_the_cornell_box_decides_like_the_conventional_test() {
    let scene = asset_scene("scenes/shadows-bunny.toml");
    assert!(scene.faces.len() > 69_000, "{} faces", scene.faces.len());
    for (scheme, nth) in [
        (SchemeChoice::Volume, Nth::Auto),
        (SchemeChoice::Hst, Nth::Fixed(16.0)),
    ] {
        let opts = Settings {
            size: Size::new(160, 120),
            ..options(scheme, nth)
        };
        assert_agrees(&scene, &opts, 10_000, "bunny");
    }
}

/// The Happy Buddha's 100,000 triangles on the floor of the box, HST with the shadow volumes
/// built in parallel from the silhouette edges alone.
#[test]
fn the_buddha_in_the_cornell_box_decides_like_the_conventional_test() {
    let scene = asset_scene("scenes/shadows-buddha.toml");
    assert!(scene.faces.len() > 100_000, "{} faces", scene.faces.len());
    let opts = Settings {
        size: Size::new(160, 120),
        ..options(SchemeChoice::Hst, Nth::Fixed(16.0))
    };
    assert_agrees(&scene, &opts, 10_000, "buddha");
}

#[test]
fn the_cornell_box_loads_with_its_colours_and_its_lights_inside_the_grid() {
    let scene = asset_scene("scenes/shadows-cornell.toml");
    // 18 faces in the file (quads), triangulated by the loader; the front wall is commented out.
    assert!(scene.faces.len() >= 30, "{} faces", scene.faces.len());
    let red = scene
        .materials
        .iter()
        .any(|m| m.diffuse.x > 0.5 && m.diffuse.y < 0.1);
    assert!(red, "the red wall's colour comes from the MTL file");
    let prep = Prepared::new(scene, Scheme::Volume);
    for l in &prep.scene.lights {
        assert!(prep.grid.bounds.grow(l.position) == prep.grid.bounds);
    }
    assert_same_as_conventional(&prep.scene, "cornell");
}

#[test]
fn malformed_mesh_objects_are_clear_errors() {
    let dir = crate::scene::assets_dir().join("scenes");
    let scene = |mesh: &str, extra: &str| {
        format!(
            "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov_y_deg = 40\n\
             [[lights]]\nposition = [0, 3, 3]\nintensity = [1, 1, 1]\n\
             [[objects]]\nmesh = \"{mesh}\"\n{extra}"
        )
    };
    let cases = [
        (scene("../malformed/obj/malformed.obj", ""), "malformed.obj"),
        (scene("../malformed/obj/empty.obj", ""), "empty.obj"),
        (scene("../malformed/obj/test-nan.obj", ""), "test-nan.obj"),
        (scene("../meshes/nope.obj", ""), "nope.obj"),
        (
            scene("../meshes/cornell_box/cornell_box.obj", "scale = -1"),
            "scale",
        ),
        (
            scene("../meshes/cornell_box/cornell_box.obj", "material = \"x\""),
            "unknown material",
        ),
    ];
    for (text, why) in cases {
        let e = Scene::parse(&text, &dir.join("bad.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("bad.toml: object 0") && e.contains(why), "{e}");
    }
}

/// The departure from the pseudo code: a self-shadowed point whose count is valid carries it
/// through (when a ray continues and N_s <= N_th), so the next point may use it; without a
/// continuing ray, or above the threshold, it drops it as the paper does.
#[test]
fn self_shadowed_points_carry_a_valid_count_on() {
    let mut s = LightState::at_eye(0);
    let (shadowed, sub) = s.hst_step(3, 8.0, true, true, || 2, || unreachable!());
    assert_eq!(
        (shadowed, sub),
        (true, crate::shadow::Subscheme::SelfShadow)
    );
    assert_eq!((s.sc, s.sdf, s.dc), (Some(true), true, 2));
    // Shadowed but counted: the next point takes the count, not a shadow ray.
    let (shadowed, sub) = s.hst_step(2, 8.0, false, true, || -2, || unreachable!());
    assert_eq!(
        (shadowed, sub),
        (false, crate::shadow::Subscheme::ShadowVolume)
    );
    let mut t = LightState::at_eye(0);
    t.hst_step(3, 8.0, true, false, || unreachable!(), || unreachable!());
    assert_eq!((t.sc, t.sdf), (Some(true), false));
    let mut u = LightState::at_eye(0);
    u.hst_step(30, 8.0, true, true, || unreachable!(), || unreachable!());
    assert!(!u.sdf);
    // Invalid count and shadowed: a shadow ray decides.
    let decided = u.hst_step(2, 8.0, false, true, || unreachable!(), || false);
    assert_eq!(decided, (false, crate::shadow::Subscheme::Conventional));
}

/// The builder refuses what would break the tracer, says which face and why, and adds nothing.
#[test]
fn the_builder_refuses_bad_faces_and_scenes_with_clear_errors() {
    use crate::scene::{BuildError, Camera, Light, Material};
    let camera = Camera {
        position: Vec3::new(0.0, 1.0, 3.0),
        target: Vec3::ZERO,
        up: Vec3::Y,
        fov_y_deg: 40.0,
    };
    let mut s = Scene::new("built", camera);
    assert!(
        matches!(s.validate(), Err(BuildError::Invalid(_))),
        "no lights"
    );
    let grey = s.add_material(Material::matte(Vec3::splat(0.5)));
    let ids: Vec<u32> = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::X * 2.0, Vec3::NAN]
        .map(|p| s.add_vertex(p))
        .to_vec();
    let errors = [
        (vec![0, 1, 9], grey),
        (vec![0, 1, 2], 7),
        (vec![0, 1, 4], grey),
        (vec![0, 1, 3], grey),
        (vec![0, 1, 1], grey),
    ]
    .map(|(v, m)| s.add_face(v, m).unwrap_err().to_string());
    for (e, why) in errors.iter().zip([
        "vertex index 9 out of range (5 vertices)",
        "material 7 out of range (1 materials)",
        "vertex 4 is not finite",
        "degenerate",
        "degenerate",
    ]) {
        assert!(e.starts_with("face 0: ") && e.contains(why), "{e}");
    }
    assert!(s.faces.is_empty());
    assert_eq!(s.add_face(ids[0..3].to_vec(), grey), Ok(0));
    // A mesh with a bad triangle is refused whole.
    let positions = [Vec3::ZERO, Vec3::Z, Vec3::X];
    assert_eq!(
        s.add_mesh(&positions, &[0, 1, 2, 0, 1], grey),
        Err(BuildError::PartialTriangle(5))
    );
    assert!(s.add_mesh(&positions, &[0, 1, 2, 0, 1, 3], grey).is_err());
    assert_eq!((s.faces.len(), s.vertices.len()), (1, 5));
    s.add_mesh(&positions, &[0, 1, 2], grey).unwrap();
    assert_eq!((s.faces.len(), s.vertices.len()), (2, 8));
    assert!(s.add_box(Vec3::ONE, Vec3::ZERO, grey).is_err());
    for _ in 0..=crate::scene::MAX_LIGHTS {
        s.add_light(Light::white(Vec3::Y * 4.0, 0.1));
    }
    assert!(s.validate().unwrap_err().to_string().contains("9 lights"));
    s.lights.truncate(1);
    s.validate().unwrap();
    s.lights[0].position.x = f32::NAN;
    let e = run(s, &options(SchemeChoice::Hst, Nth::Fixed(4.0))).unwrap_err();
    assert!(e.to_string().contains("not finite"), "{e}");
}
