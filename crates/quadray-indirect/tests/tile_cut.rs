//! The per-tile cuts on the GPU against their CPU twin (`quadray_indirect::tiles::twin`): tile for
//! tile the same nodes, except below a node whose decision the twin found a tie (its quantity
//! within `TIE` of its threshold), where f32 sums in another order may decide the other way.

use quadray_gpu::Gpu;
use quadray_indirect::tiles::deblock::deblock;
use quadray_indirect::tiles::twin::{TileInput, tile_cuts};
use quadray_indirect::{CutNode, Method, Renderer, Scene, Settings, TileCriterion};
use std::collections::BTreeSet;

/// Whether `node` is `tied` or lies below a tied node.
fn under_a_tie(node: CutNode, tied: &BTreeSet<CutNode>, root: u32) -> bool {
    (node.level..=root).any(|level| {
        let up = level - node.level;
        tied.contains(&CutNode {
            level,
            x: node.x >> up,
            y: node.y >> up,
        })
    })
}

/// One frame's tiles compared.
struct Compared {
    tiles: usize,
    /// Tiles with a list.
    lit: usize,
    /// Tiles whose coarse estimate was zero.
    zero_estimate: usize,
    equal: usize,
    /// Nodes the twin found a tie at.
    ties: usize,
    /// Tiles whose lists differ below a tie, and the nodes they differ in.
    tied: usize,
    differing: usize,
}

fn compare(gpu: &Gpu, scene: &Scene, settings: Settings) -> Compared {
    let what = format!("{} {:?}", scene.name, settings.tile_criterion);
    let mut r = Renderer::new(gpu, scene, settings.clone()).unwrap();
    let frame = r.render_frame(Method::QuadtreeTiles).unwrap();
    assert_eq!(frame.counts.refused_splits, 0, "the lists had room");
    let (nodes, bounds) = (r.read_nodes().unwrap(), r.read_node_bounds().unwrap());
    let receivers = r.read_receivers().unwrap();
    let twin = tile_cuts(&TileInput {
        nodes: &nodes,
        bounds: &bounds,
        receivers: &receivers,
        settings: &settings,
        r_min: scene.r_min,
    });
    let gpu_cuts = r.read_tile_cuts().unwrap();
    let estimates = r.read_tile_estimates().unwrap();
    assert_eq!(gpu_cuts.len(), twin.len());
    let root = settings.rsm_size.ilog2();
    let (mut lit, mut equal, mut tied, mut differing) = (0, 0, 0, 0);
    let ties = twin.iter().map(|t| t.ties.len()).sum();
    let zero_estimate = twin.iter().filter(|t| t.zero_estimate).count();
    for (tile, ((gpu_cut, cpu), estimate)) in gpu_cuts.iter().zip(&twin).zip(&estimates).enumerate()
    {
        let on_gpu: BTreeSet<CutNode> = gpu_cut.iter().copied().collect();
        let on_cpu: BTreeSet<CutNode> = cpu.nodes.iter().copied().collect();
        assert_eq!(
            on_gpu.len(),
            gpu_cut.len(),
            "{what}, tile {tile} lists a node twice"
        );
        lit += usize::from(!on_cpu.is_empty());
        if on_gpu == on_cpu {
            equal += 1;
            if cpu.ties.is_empty() {
                assert_eq!(
                    *estimate,
                    (cpu.estimated, cpu.estimate_evaluations),
                    "{what}, tile {tile}: the estimates"
                );
            }
            continue;
        }
        let ties: BTreeSet<CutNode> = cpu.ties.iter().copied().collect();
        let apart: Vec<CutNode> = on_gpu.symmetric_difference(&on_cpu).copied().collect();
        let unexplained: Vec<&CutNode> = apart
            .iter()
            .filter(|&&n| !under_a_tie(n, &ties, root))
            .collect();
        assert!(
            unexplained.is_empty(),
            "{what}, tile {tile}: the GPU's list and the twin's differ at {unexplained:?} (GPU only: {:?}, twin only: {:?}), no tie there",
            on_gpu.difference(&on_cpu).collect::<Vec<_>>(),
            on_cpu.difference(&on_gpu).collect::<Vec<_>>(),
        );
        tied += 1;
        differing += apart.len();
    }
    Compared {
        tiles: twin.len(),
        lit,
        zero_estimate,
        equal,
        ties,
        tied,
        differing,
    }
}

/// (The door scene's dark room has tiles whose coarse estimate is zero: with a threshold of zero
/// they split every node that might light them until their lists refused splits.)
#[test]
fn gpu_tile_cuts_equal_the_cpu_twin() {
    let gpu = Gpu::new().expect("an adapter (run scripts/setup.sh for lavapipe)");
    let load = |name: &str| {
        Scene::load(&quadray_indirect::scene::scenes_dir().join(format!("{name}.toml"))).unwrap()
    };
    let mut zero_estimates = 0;
    for (scene, criterion) in [
        (Scene::cornell(), TileCriterion::Estimate),
        (Scene::cornell(), TileCriterion::Bound),
        (load("atrium"), TileCriterion::Estimate),
        (load("visibility-door"), TileCriterion::Estimate),
    ] {
        let settings = Settings {
            tile_criterion: criterion,
            ..Settings::sized(64, 64, 64)
        };
        let c = compare(&gpu, &scene, settings);
        println!(
            "{} {criterion:?}: {} tiles, {} with a list, {} with a zero estimate, {} lists equal, {} tied nodes, {} tiles differing at ties ({} nodes)",
            scene.name, c.tiles, c.lit, c.zero_estimate, c.equal, c.ties, c.tied, c.differing
        );
        zero_estimates += c.zero_estimate;
        assert!(c.lit > 20, "{} tiles with a list", c.lit);
        assert!(
            c.tied * 20 <= c.lit,
            "{} of {} tiles differ at ties",
            c.tied,
            c.lit
        );
    }
    assert!(zero_estimates > 0, "no tile with a zero estimate");
}

/// The deblocking filter on the GPU against its CPU twin (`quadray_indirect::tiles::deblock`): the
/// per-tile cuts' light without it, filtered on the CPU, is the light with it, and the filter
/// changes the light at many boundaries.
#[test]
fn gpu_deblocking_equals_the_cpu_twin() {
    let gpu = Gpu::new().expect("an adapter (run scripts/setup.sh for lavapipe)");
    let scene = Scene::load(&quadray_indirect::scene::scenes_dir().join("leak.toml")).unwrap();
    // 72 x 56: the last column and row of tiles have a boundary too near the edge to filter
    let frame = |tile_deblock| {
        let settings = Settings {
            indirect_shadows: true,
            tile_deblock,
            ..Settings::sized(76, 60, 32)
        };
        let mut r = Renderer::new(&gpu, &scene, settings).unwrap();
        let frame = r.render_frame(Method::QuadtreeTiles).unwrap();
        (frame, r.read_receivers().unwrap())
    };
    let (plain, receivers) = frame(0);
    {
        let radius = Settings::DEFAULT.tile_deblock;
        let (filtered, _) = frame(radius);
        let mut twin = plain.indirect.clone();
        deblock(&mut twin, &receivers, plain.width as usize, radius as usize);
        let scale = twin.iter().flatten().fold(0.0f32, |m, v| m.max(v.abs()));
        let far = |a: &[[f32; 3]], b: &[[f32; 3]]| {
            a.iter()
                .zip(b)
                .filter(|(p, q)| (0..3).any(|c| (p[c] - q[c]).abs() > 1e-5 * scale))
                .count()
        };
        let changed = far(&plain.indirect, &twin);
        println!("radius {radius}: {changed} pixels changed");
        assert!(changed > 200, "radius {radius}: {changed} pixels changed");
        assert_eq!(far(&filtered.indirect, &twin), 0, "radius {radius}");
    }
}
