//! The work counts the shaders report (`Frame::counts`) against an independent count on the CPU
//! from what the frame read: the cut, the quadtree's nodes, the RSM's VPLs, the sample pattern and
//! the G-buffer. A 32^2 RSM keeps every per-pixel sum in one dispatch (one slice), so each indirect
//! dispatch reads a pixel's three G-buffer texels once.

use glam::{Vec2, Vec3, Vec4};
use quadray_gpu::Gpu;
use quadray_indirect::gathers::samples::{SAMPLE_SEED, rsm_samples};
use quadray_indirect::tiles::twin::{TileInput, tile_cuts};
use quadray_indirect::{
    ClusterSettings, Levels, Method, Renderer, Scene, Settings, Size, TileCriterion, Validity,
    WorkCounts,
};
use quadray_indirect::{LightView, Receiver};

const RSM: u32 = 32;

fn settings() -> Settings {
    Settings {
        size: Size::new(40, 32),
        rsm_size: RSM,
        cluster: ClusterSettings {
            validity: Validity::Recursive,
            ..ClusterSettings::DEFAULT
        },
        samples: 48,
        // the per-tile cuts' refinement and gather as the CPU recounts them: every pixel
        // evaluates its tile's list (no far clusters shared at the corners)
        tile_share: 0.0,
        ..Settings::default()
    }
}

/// A node's index in the pyramid (finest level first).
fn node_index(level: u32, x: u32, y: u32) -> usize {
    let offset: u32 = (0..level).map(|l| (RSM >> l).pow(2)).sum();
    (offset + y * (RSM >> level) + x) as usize
}

/// The top-down cut rule of `cut_rule.wgsl` over the nodes read back, with the node records it
/// reads: (in the cut, reads).
fn in_cut(nodes: &[[[f32; 4]; 3]], c: &Levels, level: u32, x: u32, y: u32) -> (bool, u64) {
    let index = node_index;
    let mut reads = 1;
    let mut accepted = |level: u32, x: u32, y: u32| {
        if level == c.limit {
            return true;
        }
        reads += 1;
        nodes[index(level, x, y)][2][3] > 0.5
    };
    let used = nodes[index(level, x, y)][0][3] >= 0.5
        && accepted(level, x, y)
        && (level + 1..=c.start).all(|a| !accepted(a, x >> (a - level), y >> (a - level)));
    (used, reads)
}

fn counted(r: &mut Renderer, method: Method) -> WorkCounts {
    let frame = r.render_frame(method).unwrap();
    println!("{method:?}: {:?}", frame.counts);
    frame.counts
}

#[test]
fn shader_counts_match_a_cpu_count_for_every_method() {
    let gpu = Gpu::new().expect("an adapter (run scripts/setup.sh for lavapipe)");
    let scene = Scene::cornell();
    let s = settings();
    let mut r = Renderer::new(&gpu, &scene, s.clone()).unwrap();
    r.render(Method::Quadtree, true, false).unwrap();
    let cut = u64::from(r.clusters_in_cut().unwrap());
    let nodes = r.read_nodes().unwrap();
    let vpls = r.read_vpls().unwrap().len() as u64;
    let receivers = r.read_receivers().unwrap();
    let pixels = u64::from(s.size.width * s.size.height);
    let shaded = receivers.iter().filter(|r| r.is_some()).count() as u64;
    assert!(
        shaded > pixels / 2 && shaded < pixels,
        "{shaded} of {pixels}"
    );
    assert!(cut > 16 && vpls > 500, "{cut} clusters, {vpls} VPLs");
    let expect = |evaluations: u64, fetches: u64| WorkCounts {
        shaded_pixels: shaded as u32,
        vpl_evaluations: evaluations,
        texel_fetches: fetches,
        bound_evaluations: 0,
        refused_splits: 0,
    };

    // the cut: every shaded pixel sums every cluster, reading its record
    let quadtree = counted(&mut r, Method::Quadtree);
    assert_eq!(quadtree, expect(shaded * cut, 3 * pixels + shaded * cut));

    // the per-level passes: one dispatch per level; each node's cut test reads records
    let c = s.levels();
    let mut level_reads = 0;
    for level in c.limit..=c.start {
        let side = RSM >> level;
        for i in 0..side * side {
            let (used, reads) = in_cut(&nodes, &c, level, i % side, i / side);
            level_reads += reads + u64::from(used);
        }
    }
    let levels = u64::from(c.start - c.limit + 1);
    let passes = counted(&mut r, Method::QuadtreePasses);
    assert_eq!(
        passes,
        expect(shaded * cut, 3 * pixels * levels + shaded * level_reads)
    );

    // the brute force: every texel's normal, the VPLs' flux and position
    let reference = counted(&mut r, Method::Reference);
    let rsm_texels = u64::from(RSM * RSM);
    assert_eq!(
        reference,
        expect(shaded * vpls, 3 * pixels + shaded * (rsm_texels + 2 * vpls))
    );

    // per-tile cuts, per tile that sees geometry: the coarse estimate (every node of the start
    // level read, the non-empty ones evaluated at each 4x4 quadrant's first covered pixel and
    // their bound records read and evaluated against both groups of receivers), the
    // refinement from the root (every node visited read; a bound record read and evaluated
    // against both groups of receivers for the non-empty ones above level 0, which are listed or
    // split, the split ones' four children visited) and the gather (the list read once into
    // workgroup memory, then each covered pixel reads and sums its nodes). With the estimate
    // criterion, the nodes whose error the tile estimated read their four children, and the
    // evaluations that took, are the CPU twin's (`tiles::twin`), but where it found a tie
    let start = c.start;
    let node_bounds = r.read_node_bounds().unwrap();
    let root = RSM.ilog2();
    let lit = |level: u32, x: u32, y: u32| nodes[node_index(level, x, y)][0][3] > 0.5;
    let start_nodes = u64::from((RSM >> start).pow(2));
    let lit_start = (0..start_nodes as u32)
        .filter(|&i| lit(start, i % (RSM >> start), i / (RSM >> start)))
        .count() as u64;
    for criterion in TileCriterion::ALL {
        let settings = Settings {
            tile_criterion: criterion,
            ..s.clone()
        };
        let mut r = Renderer::new(&gpu, &scene, settings.clone()).unwrap();
        let tiles = counted(&mut r, Method::QuadtreeTiles);
        let cuts = r.read_tile_cuts().unwrap();
        let estimates = r.read_tile_estimates().unwrap();
        let twin = tile_cuts(&TileInput {
            nodes: &nodes,
            bounds: &node_bounds,
            receivers: &receivers,
            settings: &settings,
            r_min: scene.r_min,
        });
        let (mut evaluations, mut fetches, mut bounds) = (0, 3 * pixels, 0);
        // the deblocking filter: on each line across a boundary not too near the picture's
        // edge, its window's G-buffer texels and light
        let r = s.tile_deblock;
        let boundaries = |along: u32| (8..).step_by(8).take_while(|b| b + r < along).count();
        let windows = boundaries(s.size.width) as u64 * u64::from(s.size.height)
            + boundaries(s.size.height) as u64 * u64::from(s.size.width);
        fetches += windows * u64::from(2 * r + 2) * 4;
        let tiles_x = s.size.width.div_ceil(8);
        for (tile, ((cut, &reported), twin)) in cuts.iter().zip(&estimates).zip(&twin).enumerate() {
            let (tx, ty) = (tile as u32 % tiles_x, tile as u32 / tiles_x);
            let covered = |lx: u32, ly: u32| {
                let (x, y) = (tx * 8 + lx, ty * 8 + ly);
                x < s.size.width
                    && y < s.size.height
                    && receivers[(y * s.size.width + x) as usize].is_some()
            };
            let pixels_lit = (0..64).filter(|i| covered(i % 8, i / 8)).count() as u64;
            if pixels_lit == 0 {
                assert!(cut.is_empty());
                assert_eq!(reported, (0, 0));
                continue;
            }
            let quadrants = (0..4)
                .filter(|q| (0..16).any(|i| covered(q % 2 * 4 + i % 4, q / 2 * 4 + i / 4)))
                .count() as u64;
            let split: std::collections::BTreeSet<(u32, u32, u32)> = cut
                .iter()
                .flat_map(|n| {
                    (n.level + 1..=root)
                        .map(move |a| (a, n.x >> (a - n.level), n.y >> (a - n.level)))
                })
                .collect();
            let listed = cut.len() as u64;
            let listed_above_0 = cut.iter().filter(|n| n.level > 0).count() as u64;
            if criterion == TileCriterion::Bound {
                assert_eq!(reported, (0, 0));
            } else if twin.ties.is_empty() {
                assert_eq!(
                    reported,
                    (twin.estimated, twin.estimate_evaluations),
                    "tile {tile}: nodes estimated and their evaluations, against the twin's"
                );
            }
            let (estimated, estimate_evaluations) = (u64::from(reported.0), u64::from(reported.1));
            let split = split.len() as u64;
            // a bound for each of the tile's two groups of receivers
            bounds += 2 * (lit_start + listed_above_0 + split);
            evaluations += lit_start * quadrants + pixels_lit * listed + estimate_evaluations;
            fetches += start_nodes
                + lit_start
                + (1 + 4 * split)
                + (listed_above_0 + split)
                + listed
                + pixels_lit * listed
                + 4 * estimated;
        }
        println!("per-tile cuts, {criterion:?}: {tiles:?}");
        assert_eq!(tiles.refused_splits, 0);
        assert!(bounds > 0 && tiles.vpl_evaluations > 0);
        assert_eq!(
            (
                tiles.vpl_evaluations,
                tiles.texel_fetches,
                tiles.bound_evaluations
            ),
            (evaluations, fetches, bounds)
        );
        if criterion == TileCriterion::Estimate {
            let estimated: u32 = estimates.iter().map(|e| e.0).sum();
            assert!(estimated > 0, "some node's error was estimated");
        }
    }

    // RSM sampling: the shader's disk around each receiver's projection, in f32 as there
    let samples = rsm_samples(
        s.samples,
        s.rsm_radius * RSM as f32 * std::f32::consts::SQRT_2,
        SAMPLE_SEED,
    );
    let view_proj = LightView::of_scene(&scene, 1)[0].view_proj;
    let side = RSM as f32;
    // one receiver's (evaluations, fetches) past its G-buffer reads
    let sampled = |receiver: &Receiver| {
        let (mut evaluations, mut fetches) = (0, 0);
        let clip = view_proj * Vec3::from(receiver.position).extend(1.0);
        let ndc = Vec2::new(clip.x, clip.y) / clip.w.max(1e-6);
        let projected = Vec2::new(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) * side;
        let centre = if clip.w <= 0.0 {
            Vec2::splat(0.5 * side)
        } else {
            projected.clamp(Vec2::ZERO, Vec2::splat(side))
        };
        let corner = centre.max(Vec2::splat(side) - centre);
        for sample in &samples {
            let sample = Vec4::from(*sample);
            let scale = (corner.length() / sample.w).min(1.0);
            let t = (centre + Vec2::new(sample.x, sample.y) * scale).floor();
            if t.cmpge(Vec2::ZERO).all() && t.cmplt(Vec2::splat(side)).all() {
                fetches += 1;
                let texel = (t.y as u32 * RSM + t.x as u32) as usize;
                if nodes[texel][0][3] > 0.5 {
                    evaluations += 1;
                    fetches += 2;
                }
            }
        }
        (evaluations, fetches)
    };
    let (mut evaluations, mut fetches) = (0, 3 * pixels);
    for (e, f) in receivers.iter().flatten().map(sampled) {
        evaluations += e;
        fetches += f;
    }
    let rsm = counted(&mut r, Method::Rsm);
    // a sample on a texel border may floor differently than on the GPU: 0.1% slack
    let close = |a: u64, b: u64| (a as f64 - b as f64).abs() <= 1e-3 * b as f64;
    assert!(
        close(rsm.vpl_evaluations, evaluations) && close(rsm.texel_fetches, fetches),
        "{rsm:?} against {evaluations} evaluations, {fetches} fetches"
    );
    assert!(evaluations > shaded * u64::from(s.samples) / 4);

    // sub-sampled: the low-resolution samples sum the cut, and so do the recomputed pixels
    let k = 4;
    let mut sub = Renderer::new(
        &gpu,
        &scene,
        Settings {
            subsample: k,
            ..s.clone()
        },
    )
    .unwrap();
    let frame = sub.render_frame(Method::Quadtree).unwrap();
    let low_receivers: Vec<&Receiver> = (0..s.size.height.div_ceil(k))
        .flat_map(|y| (0..s.size.width.div_ceil(k)).map(move |x| (x, y)))
        .filter_map(|(x, y)| {
            let p = |v: u32, n: u32| (v * k + k / 2).min(n - 1);
            receivers[(p(y, s.size.height) * s.size.width + p(x, s.size.width)) as usize].as_ref()
        })
        .collect();
    let low_shaded = low_receivers.len() as u64;
    let recomputed = u64::from(frame.recomputed);
    assert!(recomputed > 0 && recomputed < shaded / 2, "{recomputed}");
    println!("sub-sampled: {:?}", frame.counts);
    assert_eq!(
        frame.counts.vpl_evaluations,
        (low_shaded + recomputed) * cut
    );
    assert_eq!(frame.counts.shaded_pixels as u64, shaded);

    // RSM sampling sub-sampled: each low-resolution sample's evaluations, and each recomputed
    // pixel's (which pixels is the upsampler's choice: their sum lies between the fewest and
    // the most any pixel makes)
    let frame = sub.render_frame(Method::Rsm).unwrap();
    let low: u64 = low_receivers.iter().map(|r| sampled(r).0).sum();
    let per_pixel: Vec<u64> = receivers.iter().flatten().map(|r| sampled(r).0).collect();
    let (fewest, most) = (
        per_pixel.iter().min().unwrap(),
        per_pixel.iter().max().unwrap(),
    );
    let recomputed = u64::from(frame.recomputed);
    let rest = frame.counts.vpl_evaluations as i64 - low as i64;
    println!(
        "RSM sub-sampled: {:?}, {recomputed} recomputed",
        frame.counts
    );
    assert!(recomputed > 0 && *fewest > 0, "{recomputed} {fewest}");
    // 0.1% slack for samples on texel borders, as above
    let slack = (1e-3 * frame.counts.vpl_evaluations as f64) as i64;
    assert!(
        rest + slack >= (recomputed * fewest) as i64 && rest - slack <= (recomputed * most) as i64,
        "{rest} evaluations past the low-resolution samples' {low} for {recomputed} pixels \
         making {fewest}..{most} each"
    );
}
