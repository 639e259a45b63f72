//! The GPU paths against ground truth on whatever adapter the machine has (lavapipe in CI), at
//! tiny sizes: the GPU brute force against the CPU one, the quadtree with every cluster a single
//! VPL against the brute force, the per-level passes against the compacted cut, and the error of
//! the default thresholds.

use quadray_gpu::{Gpu, texture_2d};
use quadray_indirect::reference::{self, ImageError, compare};
use quadray_indirect::{
    ClusterSettings, CutNode, FLOAT_FORMAT, GBufferLayout, GBufferViews, Gather, LightQuadtree,
    Method, Renderer, RsmViews, Scene, Settings, Size, TileCriterion, Validity, ViewMaps,
};

fn settings(rsm_size: u32) -> Settings {
    Settings {
        samples: 64,
        ..Settings::sized(64, 64, rsm_size)
    }
}

/// rel_l1 of the per-tile cuts with the bound at its default error on the Cornell box (256^2
/// RSM, 64x64 image, far clusters shared at 2 tile extents): measured 0.0296 (lavapipe), with 52%
/// of margin.
const TILE_DEFAULT_BOUND: f64 = 0.045;
/// The same, split by the estimated error at its default (the default method): measured 0.0250
/// (lavapipe, at 410 evaluations a pixel against the bound's 576), with 80% of margin.
const TILE_ESTIMATE_DEFAULT_BOUND: f64 = 0.045;

/// How much error receiver sharing at 2 tile extents may add to the per-tile cuts at the
/// estimate's default (Cornell box, 128^2 RSM, 128x128 image): measured 0.95 (0.0261 against
/// 0.0275, at 224 evaluations a pixel against 325, lavapipe; 0.96 with a 256^2 RSM, at four times
/// the brute force's cost).
const SHARED_ERROR_FACTOR: f64 = 1.3;

/// rel_l1 between the compact and the wide layouts' pictures (Cornell box, 32x32, 512^2 RSM, whose
/// texels' flux lies below a half float's normal range; the default method): measured 2.7e-4
/// indirect and 4.2e-4 direct (lavapipe; most of it the albedo's 10 bits: 0.73 is stored as 747 /
/// 1023), with 140% of margin.
const LAYOUT_AGREEMENT: f64 = 1e-3;

fn gpu() -> Gpu {
    Gpu::new().expect("an adapter (run scripts/setup.sh for lavapipe)")
}

fn cornell(gpu: &Gpu, settings: Settings) -> Renderer<'_> {
    Renderer::new(gpu, &Scene::cornell(), settings).unwrap()
}

/// The error of `image` against `truth`, printed after `what` for the test's log.
fn logged_error(what: &str, image: &[[f32; 3]], truth: &[[f32; 3]]) -> ImageError {
    let e = compare(image, truth);
    println!("{what}: {e:?}");
    e
}

fn render(r: &mut Renderer, method: Method) -> Vec<[f32; 3]> {
    r.render_frame(method).unwrap().indirect
}

#[test]
fn gpu_brute_force_matches_the_cpu_reference() {
    let gpu = gpu();
    let scene = Scene::cornell();
    let mut r = Renderer::new(&gpu, &scene, settings(32)).unwrap();
    let gpu_image = render(&mut r, Method::Reference);
    let vpls = r.read_vpls().unwrap();
    let receivers = r.read_receivers().unwrap();
    assert!(
        vpls.len() > 500,
        "the spot sees the room: {} VPLs",
        vpls.len()
    );
    assert!(receivers.iter().filter(|r| r.is_some()).count() > 2000);
    let cpu_image = reference::brute_force(&vpls, &receivers, scene.r_min);
    let lit = cpu_image
        .iter()
        .filter(|p| p.iter().sum::<f32>() > 0.0)
        .count();
    assert!(lit > 2000, "indirect light reaches most pixels ({lit})");
    let e = logged_error("GPU vs CPU brute force", &gpu_image, &cpu_image);
    assert!(e.rel_l1 < 1e-5 && e.rel_max < 1e-4, "{e:?}");
}

/// The compact G-buffer and RSM (positions rebuilt from depth, 16-bit normals and flux, 10-bit
/// albedo) light the Cornell box as the wide ones do: the default method's indirect and the
/// direct light of the two layouts agree within their quantisation (LAYOUT_AGREEMENT).
#[test]
fn the_compact_and_wide_layouts_light_alike() {
    let gpu = gpu();
    let frame = |gbuffer_layout| {
        let s = Settings {
            gbuffer_layout,
            ..Settings::sized(32, 32, 512)
        };
        cornell(&gpu, s).render_frame(Method::DEFAULT).unwrap()
    };
    let (compact, wide) = (frame(GBufferLayout::Compact), frame(GBufferLayout::Wide));
    let indirect = logged_error(
        "indirect, compact vs wide",
        &compact.indirect,
        &wide.indirect,
    );
    let direct = logged_error("direct, compact vs wide", &compact.direct, &wide.direct);
    assert!(indirect.rel_l1 < LAYOUT_AGREEMENT, "{indirect:?}");
    assert!(direct.rel_l1 < LAYOUT_AGREEMENT, "{direct:?}");
}

#[test]
fn gpu_brute_force_sums_every_vpl_of_the_largest_rsm() {
    // 1024^2 VPLs per pixel: lavapipe ends any single loop after 65,535 iterations, so this
    // catches a brute force (or cut, or level pass) that is not split into nested loops. 2x2
    // pixels, each on a wall of the box: lavapipe runs a workgroup's invocations 8 at a time,
    // and a cut of a million clusters costs about 3 s a row of 8 (38 s for 8x8).
    let gpu = gpu();
    let scene = Scene::cornell();
    let s = Settings {
        size: Size::new(2, 2),
        ..settings(1024)
    };
    let mut r = Renderer::new(&gpu, &scene, s).unwrap();
    let gpu_image = render(&mut r, Method::Reference);
    let vpls = r.read_vpls().unwrap();
    assert!(vpls.len() > 500_000, "{} VPLs", vpls.len());
    let cpu_image = reference::brute_force(&vpls, &r.read_receivers().unwrap(), scene.r_min);
    assert!(
        cpu_image.iter().all(|p| p.iter().sum::<f32>() > 0.0),
        "indirect light reaches every pixel: {cpu_image:?}"
    );
    let e = logged_error("GPU vs CPU brute force, 1024^2 RSM", &gpu_image, &cpu_image);
    assert!(e.rel_l1 < 1e-4, "{e:?}");
    // every cluster a single VPL: a cut of a million clusters, and the per-level passes
    r.set_cluster(ClusterSettings::every_vpl()).unwrap();
    for method in [Method::Quadtree, Method::QuadtreePasses] {
        let what = format!("{method:?} with every VPL a cluster vs brute force");
        let e = logged_error(&what, &render(&mut r, method), &gpu_image);
        assert!(e.rel_l1 < 1e-4, "{e:?}");
    }
}

#[test]
fn quadtree_with_every_cluster_one_vpl_equals_the_brute_force() {
    let gpu = gpu();
    let mut s = settings(32);
    s.cluster = ClusterSettings::every_vpl();
    let mut r = cornell(&gpu, s);
    let brute = render(&mut r, Method::Reference);
    for validity in [Validity::Local, Validity::Recursive] {
        r.set_cluster(ClusterSettings {
            validity,
            ..ClusterSettings::every_vpl()
        })
        .unwrap();
        let cut = render(&mut r, Method::Quadtree);
        assert_eq!(
            r.clusters_in_cut().unwrap() as usize,
            r.read_vpls().unwrap().len(),
            "the cut is every VPL"
        );
        let passes = render(&mut r, Method::QuadtreePasses);
        for (name, image) in [("cut", cut), ("passes", passes)] {
            let what = format!("{validity:?} {name} with every VPL vs brute force");
            assert!(logged_error(&what, &image, &brute).rel_max < 1e-5, "{what}");
        }
    }
}

#[test]
fn per_level_passes_give_the_compacted_cut_image() {
    let gpu = gpu();
    let mut r = cornell(&gpu, settings(64));
    for (validity, depth, normal) in [
        (Validity::Local, 0.05, 0.9),
        (Validity::Recursive, 0.05, 0.9),
        (Validity::Local, 0.45, 0.3),
    ] {
        r.set_cluster(ClusterSettings {
            validity,
            depth_threshold: depth,
            normal_threshold: normal,
            ..ClusterSettings::with_limit_side(64, 32)
        })
        .unwrap();
        let cut = render(&mut r, Method::Quadtree);
        let clusters = r.clusters_in_cut().unwrap();
        let passes = render(&mut r, Method::QuadtreePasses);
        let e = compare(&passes, &cut);
        println!("{validity:?} {depth}/{normal}: {clusters} clusters, passes vs cut {e:?}");
        assert!(clusters > 16 && clusters < 64 * 64 / 4, "{clusters}");
        assert!(e.rel_max < 1e-5, "{e:?}");
    }
}

#[test]
fn the_cut_covers_every_lit_rsm_texel_exactly_once() {
    let gpu = gpu();
    let size = 64;
    let mut r = cornell(&gpu, settings(size));
    r.render(Method::Quadtree, true, false).unwrap();
    let cut = r.read_cut().unwrap();
    assert_eq!(cut.len() as u32, r.clusters_in_cut().unwrap());
    let c = r.settings().levels();
    let mut cover = vec![0u32; (size * size) as usize];
    for &CutNode { level, x, y } in &cut {
        assert!((c.limit..=c.start).contains(&level), "{level}");
        let side = 1 << level;
        for ty in y * side..(y + 1) * side {
            for tx in x * side..(x + 1) * side {
                cover[(ty * size + tx) as usize] += 1;
            }
        }
    }
    let flux = r.read_rsm_flux().unwrap();
    let lit = |i: usize| flux[i].iter().any(|&v| v > 0.0);
    let levels: std::collections::BTreeSet<u32> = cut.iter().map(|n| n.level).collect();
    println!("{} clusters on levels {levels:?}", cut.len());
    assert!(
        levels.len() > 1,
        "a cut on one level is no quadtree: {levels:?}"
    );
    for (i, &n) in cover.iter().enumerate() {
        assert!(n <= 1, "texel {i} is in {n} clusters");
        assert!(n == 1 || !lit(i), "lit texel {i} is in no cluster");
    }
    // the picture of it: the RSM magnified to 512 pixels with the clusters outlined
    let zoom = quadray_indirect::picture::cut_view_zoom(size);
    let picture = quadray_indirect::picture::cut_view(size, &r.read_nodes().unwrap(), &cut, zoom);
    assert_eq!((picture.width, picture.height), (512, 512));
}

/// The cut's error against the brute force on the Cornell box (256^2 RSM) at the README's
/// figures, within 10% of each: the defaults 3.7% (under the 5% target), the local rule with a
/// 64^2 limit 5.1%, the paper's settings (local rule, 32^2) 7.4%, faster and coarser.
#[test]
fn default_thresholds_give_the_readmes_error_against_the_brute_force() {
    let gpu = gpu();
    let size = 256;
    let mut r = cornell(&gpu, settings(size));
    let brute = render(&mut r, Method::Reference);
    for (name, cluster, readme) in [
        ("defaults", ClusterSettings::DEFAULT, 0.037),
        (
            "local, limit 64^2",
            ClusterSettings::with_limit_side(size, 64),
            0.051,
        ),
        (
            "paper: local, limit 32^2",
            ClusterSettings::with_limit_side(size, 32),
            0.074,
        ),
    ] {
        r.set_cluster(cluster).unwrap();
        let image = render(&mut r, Method::Quadtree);
        let what = format!("{name}, {} clusters", r.clusters_in_cut().unwrap());
        let e = logged_error(&what, &image, &brute);
        assert!(
            (e.rel_l1 - readme).abs() <= 0.1 * readme,
            "{name}: rel. L1 {} where the README states {readme}: {e:?}",
            e.rel_l1
        );
    }
}

/// Each tile's cut against the RSM: every lit texel in exactly one of its clusters (also where
/// a full list stopped the refinement); returns the mean clusters of a lit tile.
fn check_tile_cuts(r: &Renderer) -> f64 {
    let size = r.settings().rsm_size;
    let flux = r.read_rsm_flux().unwrap();
    let cuts = r.read_tile_cuts().unwrap();
    let lit: Vec<&Vec<CutNode>> = cuts.iter().filter(|c| !c.is_empty()).collect();
    assert!(
        lit.len() > cuts.len() / 2,
        "{} of {} tiles",
        lit.len(),
        cuts.len()
    );
    for cut in &lit {
        let mut cover = vec![0u32; (size * size) as usize];
        for &CutNode { level, x, y } in cut.iter() {
            let side = 1 << level;
            for ty in y * side..(y + 1) * side {
                for tx in x * side..(x + 1) * side {
                    cover[(ty * size + tx) as usize] += 1;
                }
            }
        }
        for (i, &n) in cover.iter().enumerate() {
            let is_lit = flux[i].iter().any(|&v| v > 0.0);
            assert!(
                n <= 1 && (n == 1 || !is_lit),
                "texel {i} is in {n} clusters"
            );
        }
    }
    lit.iter().map(|c| c.len()).sum::<usize>() as f64 / lit.len() as f64
}

#[test]
fn per_tile_cuts_converge_to_the_brute_force_as_their_error_bound_shrinks() {
    let gpu = gpu();
    // 32^2 VPLs: every tile's cut can hold every VPL
    let mut r = cornell(&gpu, settings(32));
    let brute = render(&mut r, Method::Reference);
    for (tile_criterion, tile_errors) in [
        (TileCriterion::Bound, [0.1, 0.02, 0.005, 0.0]),
        (TileCriterion::Estimate, [0.01, 0.002, 0.0005, 0.0]),
    ] {
        let mut errors = Vec::new();
        for tile_error in tile_errors {
            let mut r = cornell(
                &gpu,
                Settings {
                    tile_error: Some(tile_error),
                    tile_criterion,
                    // every pixel sums its own list (the corners' interpolation is not exact),
                    // and the light stays as the lists sum it
                    tile_share: 0.0,
                    tile_deblock: 0,
                    ..settings(32)
                },
            );
            let frame = r.render_frame(Method::QuadtreeTiles).unwrap();
            let clusters = check_tile_cuts(&r);
            assert_eq!(frame.counts.refused_splits, 0, "the tiles' lists had room");
            let what = format!(
                "{tile_criterion:?} {tile_error}: {clusters:.1} clusters a tile, {:.1} evaluations and {:.1} bounds a pixel",
                frame.counts.vpl_evaluations_per_pixel(),
                frame.counts.bound_evaluations_per_pixel()
            );
            errors.push(logged_error(&what, &frame.indirect, &brute).rel_l1);
        }
        assert!(
            errors.windows(2).all(|w| w[1] < w[0]),
            "{tile_criterion:?}: error falls with the threshold: {errors:?}"
        );
        // at 0 every node the bound does not rule out is split down to single VPLs (the
        // estimate is never exactly 0 where a node differs from its children): the sum is the
        // brute force's (in another order)
        assert!(errors[3] < 1e-5, "{tile_criterion:?}: {errors:?}");
    }
}

#[test]
fn a_full_tile_list_stops_refinement_and_keeps_every_vpl() {
    let gpu = gpu();
    let capacity = 16;
    let mut r = cornell(
        &gpu,
        Settings {
            tile_error: Some(0.0),
            tile_capacity: Some(capacity),
            ..settings(32)
        },
    );
    let frame = r.render_frame(Method::QuadtreeTiles).unwrap();
    let clusters = check_tile_cuts(&r);
    let most = r
        .read_tile_cuts()
        .unwrap()
        .iter()
        .map(Vec::len)
        .max()
        .unwrap();
    println!(
        "capacity {capacity}: {clusters:.1} clusters a tile, {} splits refused",
        frame.counts.refused_splits
    );
    // a split takes three more slots: a full list has fewer than three left
    let capacity = capacity as usize;
    assert!(most <= capacity && most + 3 > capacity, "{most}");
    assert!(frame.counts.refused_splits > 0);
}

#[test]
fn per_tile_cuts_at_the_default_error_stay_within_their_measured_error() {
    let gpu = gpu();
    let size = 256;
    let mut r = cornell(&gpu, settings(size));
    let brute = render(&mut r, Method::Reference);
    for (tile_criterion, bound) in [
        (TileCriterion::Bound, TILE_DEFAULT_BOUND),
        (TileCriterion::Estimate, TILE_ESTIMATE_DEFAULT_BOUND),
    ] {
        let mut r = cornell(
            &gpu,
            Settings {
                tile_criterion,
                ..settings(size)
            },
        );
        let frame = r.render_frame(Method::QuadtreeTiles).unwrap();
        let clusters = check_tile_cuts(&r);
        let what = format!(
            "{tile_criterion:?} {}: {clusters:.1} clusters a tile, {:.1} evaluations a pixel, {} splits refused",
            r.settings().tile_error_or_default(),
            frame.counts.vpl_evaluations_per_pixel(),
            frame.counts.refused_splits
        );
        let e = logged_error(&what, &frame.indirect, &brute);
        assert!(e.rel_l1 < bound, "{tile_criterion:?}: {e:?}");
    }
    // the default method (the estimate, far clusters shared) against the paper's one cut, each
    // at its defaults: measured 0.0254 rel L1 at 409 evaluations a pixel against 0.0372 at 612
    let mut r = cornell(&gpu, settings(size));
    let default = r.render_frame(Method::DEFAULT).unwrap();
    let one_cut = r.render_frame(Method::Quadtree).unwrap();
    let (default_error, one_cut_error) = (
        compare(&default.indirect, &brute).rel_l1,
        compare(&one_cut.indirect, &brute).rel_l1,
    );
    let (default_evals, one_cut_evals) = (
        default.counts.vpl_evaluations_per_pixel(),
        one_cut.counts.vpl_evaluations_per_pixel(),
    );
    println!(
        "default method: {default_error:.4} at {default_evals:.1} evaluations a pixel; one cut: \
         {one_cut_error:.4} at {one_cut_evals:.1}"
    );
    assert!(
        default_error < 0.85 * one_cut_error && default_evals < 0.7 * one_cut_evals,
        "the default method's {default_error} at {default_evals} against {one_cut_error} at \
         {one_cut_evals}"
    );
}

/// The per-tile cuts' near field (`near_field` in src/tiles/rule.wgsl): the atrium's columns stand on its
/// sun-lit floor, and the nodes around a column's foot hold the kernel's clamp, where a node's
/// children agree with it however far both are from its VPLs; there the bound decides. The
/// default method on the atrium at 64x64 with a 64^2 RSM: measured 0.0257 rel. L1 at 521
/// evaluations a pixel; with the estimate deciding there too, 0.0448 at 503 (lavapipe).
#[test]
fn near_field_nodes_are_split_by_their_bound() {
    let gpu = gpu();
    let atrium = Scene::load(&quadray_indirect::scene::scenes_dir().join("atrium.toml")).unwrap();
    let mut r = Renderer::new(&gpu, &atrium, Settings::sized(64, 64, 64)).unwrap();
    let brute = render(&mut r, Method::Reference);
    let frame = r.render_frame(Method::DEFAULT).unwrap();
    let what = format!(
        "the default method on the atrium, {:.1} evaluations a pixel",
        frame.counts.vpl_evaluations_per_pixel()
    );
    let e = logged_error(&what, &frame.indirect, &brute);
    assert!(e.rel_l1 < 0.032, "{e:?}");
}

/// Receiver sharing: a far node gathered at the tile's corners and interpolated gives each
/// corner pixel exactly what the pixel's own sum gives, costs fewer evaluations, and adds little
/// error; with nothing far enough (a huge factor) the picture is the unshared one bit for bit.
#[test]
fn shared_far_clusters_are_exact_at_tile_corners_and_cut_evaluations() {
    let gpu = gpu();
    // a 128x128 picture: at 64x64 a tile spans twice the room and little is far
    let side = 128;
    let sized = || Settings {
        samples: 64,
        ..Settings::sized(side, side, 128)
    };
    let mut r = cornell(&gpu, sized());
    let brute = render(&mut r, Method::Reference);
    let tiles = |tile_share| {
        let mut r = cornell(
            &gpu,
            Settings {
                tile_criterion: TileCriterion::Estimate,
                tile_share,
                // the light as the corners and the lists give it
                tile_deblock: 0,
                ..sized()
            },
        );
        let frame = r.render_frame(Method::QuadtreeTiles).unwrap();
        let what = format!(
            "share {tile_share}: {:.1} evaluations a pixel",
            frame.counts.vpl_evaluations_per_pixel()
        );
        let e = logged_error(&what, &frame.indirect, &brute);
        (frame, e.rel_l1)
    };
    let (own, own_error) = tiles(0.0);
    let (none_far, _) = tiles(1000.0);
    assert_eq!(own.indirect, none_far.indirect, "nothing is shared");
    let (shared, shared_error) = tiles(2.0);
    let (own_evals, shared_evals) = (
        own.counts.vpl_evaluations_per_pixel(),
        shared.counts.vpl_evaluations_per_pixel(),
    );
    assert!(
        shared_evals < 0.85 * own_evals,
        "{shared_evals} against {own_evals}"
    );
    assert!(
        shared_error < SHARED_ERROR_FACTOR * own_error,
        "{shared_error} against {own_error}"
    );
    // every tile's corner pixels (8x8 tiles)
    let mut corners = 0;
    for ty in 0..side / 8 {
        for tx in 0..side / 8 {
            for (dx, dy) in [(0, 0), (7, 0), (0, 7), (7, 7)] {
                let i = ((ty * 8 + dy) * side + tx * 8 + dx) as usize;
                let (a, b) = (own.indirect[i], shared.indirect[i]);
                for c in 0..3 {
                    assert!(
                        (a[c] - b[c]).abs() <= 1e-4 * a[c].abs().max(1e-3),
                        "corner pixel {i}: {a:?} shared {b:?}"
                    );
                }
                corners += usize::from(a[0] > 0.0);
            }
        }
    }
    assert!(corners > 400, "{corners} lit corner pixels");
}

#[test]
fn rsm_sampling_converges_to_the_brute_force() {
    let gpu = gpu();
    let mut errors = Vec::new();
    for samples in [16, 256, 4096] {
        let mut r = cornell(
            &gpu,
            Settings {
                samples,
                ..settings(32)
            },
        );
        let brute = render(&mut r, Method::Reference);
        let image = render(&mut r, Method::Rsm);
        errors.push(compare(&image, &brute).rel_l1);
    }
    println!("RSM sampling rel_l1 at 16, 256 and 4096 samples: {errors:?}");
    assert!(errors[1] < 0.7 * errors[0], "{errors:?}");
    // no bias left: receivers outside the spot's frustum (walls, ceiling) are reached too
    assert!(errors[2] < 0.03, "{errors:?}");
}

/// Interleaved sampling at 4x4: each pixel evaluates a sixteenth of the one cut or of RSM
/// sampling's samples, and the rejoined picture stays within a few times the whole sums' error
/// to the brute force.
#[test]
fn interleaved_indirect_stays_as_close_to_the_brute_force() {
    let gpu = gpu();
    // (the filter is 7 pixels wide: the picture large enough that it blurs little of the room)
    let at_128 = Settings {
        samples: 64,
        ..Settings::sized(128, 128, 64)
    };
    let mut r = cornell(&gpu, at_128.clone());
    let brute = render(&mut r, Method::Reference);
    for method in [Method::Quadtree, Method::Rsm] {
        let whole = r.render_frame(method).unwrap();
        let mut interleaved = cornell(
            &gpu,
            Settings {
                interleave: 4,
                ..at_128.clone()
            },
        );
        let frame = interleaved.render_frame(method).unwrap();
        let (e, e_whole) = (
            compare(&frame.indirect, &brute),
            compare(&whole.indirect, &brute),
        );
        let evaluations =
            frame.counts.vpl_evaluations_per_pixel() / whole.counts.vpl_evaluations_per_pixel();
        println!(
            "{method} to the brute force, interleave 4: {e:?}, whole: {e_whole:?}; \
             {evaluations:.3} of the evaluations, {} pixels recomputed",
            frame.recomputed
        );
        assert!(frame.recomputed < 128 * 128 / 4, "{}", frame.recomputed);
        assert!(evaluations < 0.25, "{evaluations}");
        // (measured 2.2x for the cut and 1.0x for RSM sampling; the filter's 7 pixels are a
        // nineteenth of the picture here, a 270th at 1920x1080)
        assert!(e.rel_l1 < 3.0 * e_whole.rel_l1, "{e:?} against {e_whole:?}");
    }
}

#[test]
fn subsampled_indirect_stays_close_to_full_resolution() {
    let gpu = gpu();
    let mut r = cornell(&gpu, settings(32));
    let full = render(&mut r, Method::Quadtree);
    let mut r = cornell(
        &gpu,
        Settings {
            subsample: 4,
            ..settings(32)
        },
    );
    let frame = r.render_frame(Method::Quadtree).unwrap();
    let e = compare(&frame.indirect, &full);
    println!(
        "subsample 4 vs full: {e:?}, {} pixels recomputed",
        frame.recomputed
    );
    assert!(frame.recomputed > 0 && frame.recomputed < 64 * 64 / 2);
    assert!(e.rel_l1 < 0.10, "{e:?}");
}

/// A device below what the settings need is refused before anything is created, naming the
/// limit, the device's value and the setting: WebGL2-class limits (2048^2 textures, 4 storage
/// buffers a stage, 16 KiB of workgroup memory) against 4096x4096 and the gather's buffers.
#[test]
fn a_device_below_the_settings_limits_is_refused_by_name() {
    let mut settings = Settings::DEFAULT;
    settings.size = quadray_indirect::Size::new(4096, 4096);
    let needs = quadray_indirect::Gather::limit_needs(&settings);
    let small = wgpu::Limits::downlevel_webgl2_defaults();
    let error = quadray_gpu::check_limits(&small, "a WebGL2 device", &needs).unwrap_err();
    assert_eq!(
        error.to_string(),
        "a WebGL2 device allows max_texture_dimension_2d = 2048, but --size 4096x4096 needs 4096"
    );
    let default_needs = quadray_indirect::Gather::limit_needs(&Settings::DEFAULT);
    let gles = wgpu::Limits::downlevel_defaults();
    let error = quadray_gpu::check_limits(&gles, "a GLES device", &default_needs)
        .unwrap_err()
        .to_string();
    assert!(
        error.starts_with("a GLES device allows max_storage_buffers_per_shader_stage = 4, but the gather passes needs"),
        "{error}"
    );
    // lavapipe holds the defaults, but binds at most 128 MiB: not a vec4 a pixel at 4096x4096
    let lavapipe = gpu().device.limits();
    quadray_gpu::check_limits(&lavapipe, "lavapipe", &default_needs).unwrap();
    let error = quadray_gpu::check_limits(&lavapipe, "lavapipe", &needs).unwrap_err();
    assert_eq!(
        error.to_string(),
        "lavapipe allows max_storage_buffer_binding_size = 134217728, but --size 4096x4096 \
         needs 268435456"
    );
}

/// A device opened below what the settings need (lavapipe held to 1 MiB a storage binding, as
/// a small GPU) is refused by [`Renderer::new`] and by [`Gather::new`] on the caller's device
/// before any pass is made, with quadray's message rather than wgpu's validation error.
#[test]
fn renderer_and_gather_refuse_a_device_below_the_settings_by_name() {
    let adapter = gpu().adapter.clone();
    let limits = wgpu::Limits {
        max_storage_buffer_binding_size: 1 << 20,
        ..adapter.limits()
    };
    let small = Gpu::with_limits(adapter, limits).unwrap();
    // a vec4 of radiance a pixel: 4 MiB at 512x512
    let settings = Settings::sized(512, 512, 16);
    let refusal = "allows max_storage_buffer_binding_size = 1048576, but --size 512x512 needs \
                   4194304";
    let error = Renderer::new(&small, &Scene::cornell(), settings.clone())
        .err()
        .expect("refused")
        .to_string();
    assert_eq!(error, format!("{} {refusal}", small.describe()));
    let d = &small.device;
    let usage = wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::STORAGE_BINDING;
    let texture = |size| texture_2d(d, "input", size, FLOAT_FORMAT, usage);
    let (gbuffer, rsm) = (
        [(); 3].map(|_| texture((512, 512))),
        [(); 3].map(|_| texture((16, 16))),
    );
    let view = |t: &wgpu::Texture| t.create_view(&Default::default());
    let ([position, normal, albedo], [flux, rsm_position, rsm_normal]) =
        (gbuffer.each_ref().map(view), rsm.each_ref().map(view));
    let rsm = RsmViews::Wide {
        flux: &flux,
        position: &rsm_position,
        normal: &rsm_normal,
    };
    let quadtree = LightQuadtree::new(d, &small.queue, 16, settings.cluster, rsm);
    let maps = [ViewMaps {
        rsm,
        quadtree: &quadtree,
    }];
    let gbuffer = GBufferViews::Wide {
        position: &position,
        normal: &normal,
        albedo: &albedo,
    };
    let made = small.checked(|| Gather::new(d, &settings, &maps, gbuffer).map(|_| ()));
    let error = made.unwrap().expect_err("refused").to_string();
    assert_eq!(error, format!("the device {refusal}"));
}

/// Each refusal names the parameter and its range.
#[test]
fn absurd_settings_are_refused() {
    let gpu = gpu();
    let scene = Scene::cornell();
    let tile_lists = format!(
        "over {} MiB: lower the tile capacity to",
        Settings::MAX_TILE_LIST_BYTES >> 20
    );
    for (bad, what, range) in [
        (
            Settings {
                rsm_size: 48,
                ..settings(32)
            },
            "RSM size 48 must be a power of two in",
            Settings::RSM_SIZE.to_string(),
        ),
        (
            Settings {
                cluster: ClusterSettings {
                    limit_level: Some(4),
                    start_level: Some(2),
                    ..ClusterSettings::DEFAULT
                },
                ..settings(32)
            },
            "levels must satisfy limit (4) <= start (2)",
            "<= 5 (the 1x1 level of a 32 RSM)".to_string(),
        ),
        (
            Settings {
                cluster: ClusterSettings {
                    depth_threshold: f32::NAN,
                    ..ClusterSettings::DEFAULT
                },
                ..settings(32)
            },
            "depth threshold NaN",
            ClusterSettings::DEPTH_THRESHOLD.to_string(),
        ),
        (
            Settings {
                size: Size::new(0, 32),
                ..settings(32)
            },
            "size 0x32",
            Settings::SIDE.to_string(),
        ),
        (
            Settings {
                temporal_weight: 0.0,
                ..settings(32)
            },
            "temporal weight 0",
            Settings::TEMPORAL_WEIGHT.to_string(),
        ),
        (
            Settings {
                temporal_weight: f32::NAN,
                ..settings(32)
            },
            "temporal weight NaN",
            Settings::TEMPORAL_WEIGHT.to_string(),
        ),
        (
            Settings {
                tile_error: Some(-0.1),
                ..settings(32)
            },
            "tile error -0.1",
            Settings::TILE_ERROR.to_string(),
        ),
        (
            Settings {
                tile_capacity: Some(2048),
                ..settings(32)
            },
            "tile capacity 2048",
            Settings::TILE_CAPACITY.to_string(),
        ),
        (
            Settings {
                tile_capacity: Some(1024),
                ..Settings::sized(4096, 4096, 32)
            },
            "per-tile cuts of 1024 nodes for a 4096x4096 picture",
            tile_lists.clone(),
        ),
    ] {
        let e = match Renderer::new(&gpu, &scene, bad) {
            Ok(_) => panic!("{what}: accepted"),
            Err(e) => e.to_string(),
        };
        assert!(
            e.starts_with(&format!("invalid parameters: {what}")) && e.contains(&range),
            "{e}"
        );
    }
}

/// The temporal filter against its CPU ground truth: the running average of the frames an
/// unfiltered renderer makes under a turning light, at full resolution and sub-sampled; the brute
/// force neither filtered nor disturbing the average; and, the camera moved, the average
/// reprojected on the CPU from the last frame's points (bilinear over the pixels that saw the same
/// surface) blended with the new frame.
#[test]
fn temporal_filter_is_the_running_average_of_the_unfiltered_frames() {
    let gpu = gpu();
    let scene = Scene::cornell();
    let weight = 0.25;
    for subsample in [1, 2] {
        let plain_settings = Settings {
            subsample,
            ..settings(32)
        };
        let filtered_settings = Settings {
            temporal_weight: weight,
            ..plain_settings.clone()
        };
        let mut plain = Renderer::new(&gpu, &scene, plain_settings).unwrap();
        let mut filtered = Renderer::new(&gpu, &scene, filtered_settings).unwrap();
        let mut average: Option<Vec<[f32; 3]>> = None;
        for frame in 0..4 {
            let turned = scene.light_turned(5.0 * frame as f32);
            plain.set_view(&turned).unwrap();
            filtered.set_view(&turned).unwrap();
            let now = render(&mut plain, Method::Quadtree);
            let brute_force = render(&mut filtered, Method::Reference);
            assert!(compare(&brute_force, &render(&mut plain, Method::Reference)).rel_l1 < 1e-6);
            let shown = render(&mut filtered, Method::Quadtree);
            let expected: Vec<[f32; 3]> = match &average {
                None => now.clone(),
                Some(last) => last
                    .iter()
                    .zip(&now)
                    .map(|(a, n)| std::array::from_fn(|c| a[c] + weight * (n[c] - a[c])))
                    .collect(),
            };
            let e = compare(&shown, &expected);
            println!("subsample {subsample}, frame {frame}: filtered vs CPU average {e:?}");
            assert!(e.rel_l1 < 1e-5, "frame {frame}: {e:?}");
            if frame > 0 {
                // the light moved: the average is not this frame's light
                assert!(compare(&shown, &now).rel_l1 > 1e-3, "frame {frame}");
            }
            average = Some(expected);
        }
        // the camera moves twice: the second move reads what the first wrote (the normals too)
        let mut last = filtered.read_receivers().unwrap();
        let mut last_view = scene.light_turned(15.0).camera_view_proj(1.0);
        for (turn, orbit) in [(20.0, 3.0), (25.0, 8.0)] {
            let moved = scene.light_turned(turn).camera_orbited(orbit);
            plain.set_view(&moved).unwrap();
            filtered.set_view(&moved).unwrap();
            let now = render(&mut plain, Method::Quadtree);
            let shown = render(&mut filtered, Method::Quadtree);
            let points = filtered.read_receivers().unwrap();
            let expected = reprojected_average(
                average.as_deref().unwrap(),
                &last,
                last_view,
                &points,
                &now,
                weight,
            );
            let e = compare(&shown, &expected);
            println!(
                "subsample {subsample}, camera moved {orbit} deg: filtered vs CPU reprojection {e:?}"
            );
            assert!(e.rel_l1 < 1e-3, "reprojected: {e:?}");
            assert!(compare(&shown, &now).rel_l1 > 1e-3, "the average is kept");
            (average, last, last_view) = (Some(expected), points, moved.camera_view_proj(1.0));
        }
    }
}

/// The temporal filter's reprojection on the CPU (64x64): each pixel's point projected with the
/// view of the last frame, the `average` read bilinearly from the pixels whose point there lies
/// at the same depth (within 1%) with an agreeing normal (dot >= 0.9), moved `weight` of the way
/// to `now`; points not seen start anew.
fn reprojected_average(
    average: &[[f32; 3]],
    last: &[Option<quadray_indirect::Receiver>],
    last_view: glam::Mat4,
    points: &[Option<quadray_indirect::Receiver>],
    now: &[[f32; 3]],
    weight: f32,
) -> Vec<[f32; 3]> {
    let side = 64usize;
    let seen_then = |i: usize| {
        last[i].map(|r| {
            let depth = (last_view * glam::Vec3::from(r.position).extend(1.0)).w;
            (depth, glam::Vec3::from(r.normal))
        })
    };
    points
        .iter()
        .zip(now)
        .map(|(point, now)| {
            let Some(point) = point else { return *now };
            let normal = glam::Vec3::from(point.normal);
            let then = last_view * glam::Vec3::from(point.position).extend(1.0);
            if then.w <= 0.0 {
                return *now;
            }
            let x = (then.x / then.w * 0.5 + 0.5) * side as f32 - 0.5;
            let y = (0.5 - then.y / then.w * 0.5) * side as f32 - 0.5;
            let (x0, y0) = (x.floor(), y.floor());
            let (fx, fy) = (x - x0, y - y0);
            let (mut sum, mut total) = ([0.0f32; 3], 0.0f32);
            for (dx, dy) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
                let (qx, qy) = (x0 + dx, y0 + dy);
                if qx < 0.0 || qy < 0.0 || qx >= side as f32 || qy >= side as f32 {
                    continue;
                }
                let q = qy as usize * side + qx as usize;
                let same = seen_then(q).is_some_and(|(depth, n)| {
                    (depth - then.w).abs() <= 0.01 * then.w && n.dot(normal) >= 0.9
                });
                if same {
                    let w = (if dx > 0.0 { fx } else { 1.0 - fx })
                        * (if dy > 0.0 { fy } else { 1.0 - fy });
                    for c in 0..3 {
                        sum[c] += w * average[q][c];
                    }
                    total += w;
                }
            }
            if total <= 0.01 {
                return *now;
            }
            std::array::from_fn(|c| {
                let a = sum[c] / total;
                a + weight * (now[c] - a)
            })
        })
        .collect()
}

/// The pyramid and validity maps as built on the GPU, checked node by node on the CPU: sums of
/// flux and texel counts, weighted means, and both validity rules.
#[test]
fn quadtree_nodes_match_a_cpu_rebuild() {
    let gpu = gpu();
    let size = 32u32;
    let mut r = cornell(&gpu, settings(size));
    for validity in [Validity::Local, Validity::Recursive] {
        let cluster = ClusterSettings {
            validity,
            ..ClusterSettings::DEFAULT
        };
        r.set_cluster(cluster).unwrap();
        r.render(Method::Quadtree, true, false).unwrap();
        let nodes = r.read_nodes().unwrap();
        let mut offset = 0usize;
        let mut valid_above_zero = 0;
        for level in 1..=size.ilog2() {
            let child_side = (size >> (level - 1)) as usize;
            let side = child_side / 2;
            let child_offset = offset;
            offset += child_side * child_side;
            for y in 0..side {
                for x in 0..side {
                    let node = nodes[offset + y * side + x];
                    let children: Vec<_> = (0..4)
                        .map(|c| nodes[child_offset + (2 * y + c / 2) * child_side + 2 * x + c % 2])
                        .collect();
                    let count: f32 = children.iter().map(|c| c[0][3]).sum();
                    let flux: f32 = children.iter().map(|c| c[0][0]).sum();
                    assert_eq!(node[0][3], count);
                    assert!((node[0][0] - flux).abs() <= 1e-5 * flux.abs() + 1e-12);
                    let lum = |c: &[[f32; 4]; 3]| {
                        quadray_core::image_out::luminance([c[0][0], c[0][1], c[0][2]])
                    };
                    let weight: f32 = children.iter().map(lum).sum();
                    if weight > 0.0 {
                        let depth: f32 =
                            children.iter().map(|c| lum(c) * c[1][3]).sum::<f32>() / weight;
                        assert!(
                            (node[1][3] - depth).abs() < 1e-4,
                            "{} vs {depth}",
                            node[1][3]
                        );
                    }
                    let mut valid = true;
                    for c in children.iter().filter(|c| c[0][3] > 0.5) {
                        let dot: f32 = (0..3).map(|i| c[2][i] * node[2][i]).sum();
                        valid &= (c[1][3] - node[1][3]).abs() < cluster.depth_threshold
                            && dot > cluster.normal_threshold
                            && (validity == Validity::Local || c[2][3] > 0.5);
                    }
                    assert_eq!(node[2][3] > 0.5, valid, "level {level} node {x},{y}");
                    valid_above_zero += usize::from(valid && count > 0.0);
                }
            }
        }
        assert!(valid_above_zero > 10, "some clusters are valid");
    }
}

#[test]
fn node_bounds_hold_exactly_the_vpls_of_their_nodes() {
    let gpu = gpu();
    let size = 32u32;
    let mut r = cornell(&gpu, settings(size));
    r.render(Method::QuadtreeTiles, true, false).unwrap();
    let nodes = r.read_nodes().unwrap();
    let bounds = r.read_node_bounds().unwrap();
    let (mut offset, mut narrow) = (0usize, 0);
    for level in 0..=size.ilog2() {
        let side = size >> level;
        for i in 0..side * side {
            let (x, y) = (i % side, i / side);
            let node = nodes[offset + i as usize];
            let [lo, hi] = bounds[offset + i as usize];
            // the node's VPLs: the level-0 texels under it that see geometry
            let mut box_lo = [f32::MAX; 3];
            let mut box_hi = [f32::MIN; 3];
            let mut least_cos = 1.0f32;
            for ty in y << level..(y + 1) << level {
                for tx in x << level..(x + 1) << level {
                    let vpl = nodes[(ty * size + tx) as usize];
                    if vpl[0][3] < 0.5 {
                        continue;
                    }
                    for c in 0..3 {
                        box_lo[c] = box_lo[c].min(vpl[1][c]);
                        box_hi[c] = box_hi[c].max(vpl[1][c]);
                    }
                    least_cos = least_cos.min((0..3).map(|c| vpl[2][c] * node[2][c]).sum());
                }
            }
            if node[0][3] < 0.5 {
                assert!((0..3).all(|c| lo[c] > hi[c]), "empty node {level} {x},{y}");
                continue;
            }
            assert_eq!((&lo[..3], &hi[..3]), (&box_lo[..], &box_hi[..]));
            // the cone holds every VPL normal (less f32's rounding), and is not the sphere
            assert!(lo[3] <= least_cos + 1e-5, "{} > {least_cos}", lo[3]);
            narrow += usize::from(level > 0 && lo[3] > 0.9);
        }
        offset += (side * side) as usize;
    }
    assert!(narrow > 100, "{narrow} narrow cones above level 0");
}

/// The RSM's VPLs carry the flux the spot sends into its cone: with every ray of the cone landing
/// on the floor, sum(flux / albedo) = integral of I(w) over the sphere (texel solid angles
/// shrink as cos^3 off the axis).
#[test]
fn rsm_flux_adds_up_to_the_light_sent_into_the_cone() {
    let gpu = gpu();
    let scene = Scene::parse(
        r#"
        [camera]
        position = [2.0, 2.0, 6.0]
        target = [2.0, 1.0, 2.0]
        fov_deg = 40.0
        [light]
        position = [2.0, 1.0, 2.0]
        direction = [0.0, -1.0, 0.0]
        cone_deg = 30.0
        falloff_deg = 10.0
        intensity = [3.0, 3.0, 3.0]
        [[mesh]]
        builtin = "room"
        scale = 4.0
        albedo = [0.5, 0.5, 0.5]
        "#,
        "floor",
    )
    .unwrap();
    let mut r = Renderer::new(&gpu, &scene, settings(64)).unwrap();
    r.render(Method::Reference, true, false).unwrap();
    let sent: f64 = r
        .read_vpls()
        .unwrap()
        .iter()
        .map(|v| f64::from(v.flux[0]) / 0.5)
        .sum();
    // 2 pi * integral over theta of I(theta) sin(theta), smoothstep edge from 30 to 20 degrees
    let (outer, inner) = (30f64.to_radians().cos(), 20f64.to_radians().cos());
    let steps = 100_000;
    let expected: f64 = (0..steps)
        .map(|i| {
            let theta = (i as f64 + 0.5) / steps as f64 * std::f64::consts::FRAC_PI_2;
            let t = ((theta.cos() - outer) / (inner - outer)).clamp(0.0, 1.0);
            3.0 * t * t * (3.0 - 2.0 * t) * theta.sin()
        })
        .sum::<f64>()
        * std::f64::consts::FRAC_PI_2
        / steps as f64
        * std::f64::consts::TAU;
    println!("RSM flux {sent} vs emitted {expected}");
    assert!((sent / expected - 1.0).abs() < 1e-3, "{sent} vs {expected}");
}

/// A renderer whose camera moved draws what a new one at the new view draws, for the per-tile
/// cuts too: a tile that sees nothing now writes no light (it kept the last view's, which
/// the next frames showed on the background: 9.1% rel. L1 at this size).
#[test]
fn a_moved_camera_renders_the_new_view_alone() {
    let gpu = gpu();
    let before = Scene::cornell();
    let mut after = before.clone();
    after.camera.target = glam::Vec3::new(0.67, 0.5, 1.41);
    let s = Settings::sized(96, 72, 32);
    for method in Method::ALL {
        let mut moved = Renderer::new(&gpu, &before, s.clone()).unwrap();
        render(&mut moved, method);
        moved.set_view(&after).unwrap();
        let moved = render(&mut moved, method);
        let fresh = render(&mut Renderer::new(&gpu, &after, s.clone()).unwrap(), method);
        // the same up to the last bits of float sums (the one cut: 4e-8)
        let e = compare(&moved, &fresh);
        assert!(e.rel_l1 < 1e-6, "{method:?}: {e:?} against a new renderer");
    }
}
