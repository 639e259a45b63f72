//! `quadray bench indirect --cut-study`: what limits a per-tile cut of the light quadtree, on the
//! CPU from what the GPU rendered (the RSM's texels and the G-buffer, read back). Every 8x8 tile
//! refines the quadtree from its root as `--method quadtree-tiles --tile-criterion estimate`
//! does (the coarse estimate from the start level's nodes at the first covered pixel of each
//! quadrant, every node down to the start level split (the shader splits
//! those by its bound, which is far above the threshold there), below it a node split while its error at
//! those pixels and at the tile's receiver nearest it exceeds `tau` of the estimate, or while it
//! holds the kernel's near field for the tile, where the shader's bound splits it; no bound, no
//! list capacity), with three ways to know a node's error:
//! - children: |E(node) - sum E(children)|, the shader's estimate;
//! - grandchildren: |E(node) - sum E(grandchildren)|, two levels down;
//! - oracle: |E(node) - the sum over the node's VPLs|, the error itself (its kernels are not
//!   counted: no renderer could afford them);
//!
//! and two representatives of a cluster: a point VPL at its flux-weighted mean (the shader's),
//! and the same with the second-order term of the kernel's Taylor series over the VPLs'
//! positions (their covariance, reduced with the pyramid). The error is rel_l1 against the CPU
//! brute force; the counts are the cut's clusters summed per pixel and the criterion's kernels
//! per pixel (shared by a tile's pixels, as the shader counts them).

use crate::report::{PlotSpec, Series, Table, line_plot};
use glam::DVec3;
use quadray_core::{write_json, write_text};
use quadray_gpu::Gpu;
use quadray_indirect::reference::{LUMINANCE, brute_force, compare, vpl_kernel};
use quadray_indirect::tiles::twin::{self, TILE_PIXELS};
use quadray_indirect::{IndirectError, Method, Renderer, Scene, Settings};
use rayon::prelude::*;
use serde::Serialize;
use std::f64::consts::PI;
use std::path::Path;

/// Error fractions of the tile's estimated irradiance swept (the shader's `--tile-error`).
const TAUS: [f64; 5] = [0.01, 0.002, 0.0005, 0.0002, 0.00005];
/// The tile's side in pixels (the shader's `TILE`).
const TILE: usize = TILE_PIXELS.isqrt();
/// Pixel and VPL pairs the CPU brute force (and the oracle, as much again) may sum: the
/// default 128x128 picture over a 256^2 RSM is 2^30, about 20 s a scene on two cores.
const MAX_PAIRS: u64 = 1 << 32;

/// How a node's error is known when deciding to split it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Criterion {
    /// Against its four children, as the shader estimates.
    Children,
    /// Against its sixteen grandchildren.
    Grandchildren,
    /// Against the exact sum over its VPLs (uncounted).
    Oracle,
}

/// What stands for a cluster in the sum.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Representative {
    /// A point VPL with the cluster's flux at its mean position and mean normal.
    Point,
    /// The point plus the second-order term over the positions' covariance.
    SecondOrder,
}

/// One setting's error and cost.
#[derive(Clone, Debug, Serialize)]
pub struct StudyPoint {
    /// How the split was decided.
    pub criterion: Criterion,
    /// What stood for a cluster.
    pub representative: Representative,
    /// The error fraction.
    pub tau: f64,
    /// Relative L1 error of the indirect term against the brute force.
    pub rel_l1: f64,
    /// Clusters summed per shaded pixel.
    pub cut_per_pixel: f64,
    /// Kernels the criterion evaluated per shaded pixel (0 for the oracle).
    pub criterion_per_pixel: f64,
}

/// One scene's sweep.
#[derive(Clone, Debug, Serialize)]
pub struct StudyScene {
    /// The scene's name.
    pub scene: String,
    /// RSM side.
    pub rsm_size: u32,
    /// Every setting.
    pub points: Vec<StudyPoint>,
}

/// A cluster of VPLs: summed flux, the weights (flux luminance) of its mean, mean position,
/// summed weighted normal, and the weighted covariance of its positions (xx, yy, zz, xy, xz, yz).
#[derive(Clone, Copy, Default)]
struct Cluster {
    flux: DVec3,
    weight: f64,
    mean: DVec3,
    normal_sum: DVec3,
    covariance: [f64; 6],
    lit: bool,
    /// The box of its VPLs' positions.
    lo: DVec3,
    hi: DVec3,
}

impl Cluster {
    fn joined(children: &[Cluster; 4]) -> Cluster {
        let lit: Vec<&Cluster> = children.iter().filter(|c| c.lit).collect();
        let weight: f64 = lit.iter().map(|c| c.weight).sum();
        if lit.is_empty() || weight <= 0.0 {
            return Cluster::default();
        }
        let mean = lit.iter().map(|c| c.weight * c.mean).sum::<DVec3>() / weight;
        let mut covariance = [0.0; 6];
        for c in &lit {
            let e = c.mean - mean;
            let apart = [
                e.x * e.x,
                e.y * e.y,
                e.z * e.z,
                e.x * e.y,
                e.x * e.z,
                e.y * e.z,
            ];
            for ((sum, own), apart) in covariance.iter_mut().zip(c.covariance).zip(apart) {
                *sum += c.weight * (own + apart) / weight;
            }
        }
        Cluster {
            flux: lit.iter().map(|c| c.flux).sum(),
            weight,
            mean,
            normal_sum: lit.iter().map(|c| c.normal_sum).sum(),
            covariance,
            lit: true,
            lo: lit.iter().map(|c| c.lo).fold(DVec3::INFINITY, DVec3::min),
            hi: lit
                .iter()
                .map(|c| c.hi)
                .fold(DVec3::NEG_INFINITY, DVec3::max),
        }
    }

    /// The covariance times `v`.
    fn spread(&self, v: DVec3) -> DVec3 {
        let c = &self.covariance;
        DVec3::new(
            c[0] * v.x + c[3] * v.y + c[4] * v.z,
            c[3] * v.x + c[1] * v.y + c[5] * v.z,
            c[4] * v.x + c[5] * v.y + c[2] * v.z,
        )
    }

    /// Irradiance (rgb) at `x` (normal `n`): flux / pi times the reference's [`vpl_kernel`], with
    /// the second-order term where asked and where both cosines are positive (the kernel is
    /// smooth there).
    fn irradiance(&self, x: DVec3, n: DVec3, r_min: f64, representative: Representative) -> DVec3 {
        let np = self.normal_sum.normalize_or_zero();
        let d = x - self.mean;
        let mut kernel = vpl_kernel(d, n, np, r_min);
        if !self.lit || kernel == 0.0 {
            return DVec3::ZERO;
        }
        if representative == Representative::SecondOrder {
            let (a, b) = (np.dot(d), -n.dot(d));
            let q = d.dot(d);
            let r2 = r_min * r_min;
            // half the trace of the kernel's Hessian in the VPL position times the covariance
            let c = &self.covariance;
            let trace = c[0] + c[1] + c[2];
            let (c_np, c_d) = (self.spread(np), self.spread(d));
            let term = if q <= r2 {
                -2.0 * n.dot(c_np) / (r2 * r2)
            } else {
                let (q2, q3) = (q * q, q * q * q);
                -2.0 * n.dot(c_np) / q2 - 8.0 * b * c_np.dot(d) / q3
                    + 8.0 * a * n.dot(c_d) / q3
                    + 24.0 * a * b * d.dot(c_d) / (q2 * q2)
                    - 4.0 * a * b * trace / q3
            };
            kernel = (kernel + 0.5 * term).max(0.0);
        }
        self.flux * (kernel / PI)
    }
}

/// Luminance in f64, the study's precision, with the product's weights.
fn luminance(c: DVec3) -> f64 {
    c.dot(DVec3::from(LUMINANCE))
}

/// The quadtree over the RSM's texels, finest level first.
struct Pyramid {
    levels: Vec<Vec<Cluster>>,
    side: usize,
}

/// A node: level, column, row.
type NodeAt = (usize, usize, usize);

impl Pyramid {
    fn build(texels: Vec<Cluster>, side: usize) -> Self {
        let mut levels = vec![texels];
        let mut s = side;
        while s > 1 {
            let below = levels.last().unwrap();
            let half = s / 2;
            let at = |x: usize, y: usize| below[y * s + x];
            let level = (0..half * half)
                .map(|i| {
                    let (x, y) = (2 * (i % half), 2 * (i / half));
                    Cluster::joined(&[at(x, y), at(x + 1, y), at(x, y + 1), at(x + 1, y + 1)])
                })
                .collect();
            levels.push(level);
            s = half;
        }
        Self { levels, side }
    }

    fn top(&self) -> usize {
        self.levels.len() - 1
    }

    fn node(&self, (level, x, y): NodeAt) -> &Cluster {
        &self.levels[level][y * (self.side >> level) + x]
    }

    fn children((level, x, y): NodeAt) -> [NodeAt; 4] {
        let l = level - 1;
        let (x, y) = (2 * x, 2 * y);
        [(l, x, y), (l, x + 1, y), (l, x, y + 1), (l, x + 1, y + 1)]
    }

    /// The nodes `depth` levels below `at` (at most down to the VPLs).
    fn descendants(&self, at: NodeAt, depth: usize) -> Vec<NodeAt> {
        let mut nodes = vec![at];
        for _ in 0..depth.min(at.0) {
            nodes = nodes.into_iter().flat_map(Self::children).collect();
        }
        nodes
    }
}

/// A G-buffer texel: position, normal, albedo.
type Receiver = (DVec3, DVec3, DVec3);

/// One tile's cut and the kernels its criterion took.
fn tile_cut(
    pyramid: &Pyramid,
    receivers: &[&Receiver],
    samples: &[&Receiver],
    r_min: f64,
    setting: (Criterion, Representative, f64),
) -> (Vec<NodeAt>, f64) {
    let (criterion, representative, tau) = setting;
    let light =
        |c: &Cluster, r: &Receiver| luminance(c.irradiance(r.0, r.1, r_min, representative));
    let start = pyramid.top().saturating_sub(3);
    let estimate = samples
        .iter()
        .map(|r| {
            pyramid.levels[start]
                .iter()
                .map(|c| light(c, r))
                .sum::<f64>()
        })
        .sum::<f64>()
        / samples.len() as f64;
    let threshold = tau * estimate;
    let mut kernels = 0.0;
    let mut list = Vec::new();
    let mut frontier = vec![(pyramid.top(), 0, 0)];
    while let Some(at) = frontier.pop() {
        let node = pyramid.node(at);
        if !node.lit {
            continue;
        }
        // (the shader's bound splits a node in its near field: the study has no bound)
        let near_field = || {
            let positions = receivers.iter().map(|r| r.0.as_vec3());
            twin::near_field(
                node.lo.as_vec3(),
                node.hi.as_vec3(),
                positions,
                r_min as f32,
            )
        };
        let split = at.0 >= start
            || (at.0 > 0 && criterion != Criterion::Oracle && near_field())
            || (at.0 > 0 && {
                let nearest = receivers
                    .iter()
                    .min_by(|a, b| {
                        let (da, db) = (a.0.distance(node.mean), b.0.distance(node.mean));
                        da.total_cmp(&db)
                    })
                    .unwrap();
                let finer = match criterion {
                    Criterion::Children => pyramid.descendants(at, 1),
                    Criterion::Grandchildren => pyramid.descendants(at, 2),
                    Criterion::Oracle => pyramid.descendants(at, at.0),
                };
                let finer_representative = match criterion {
                    Criterion::Oracle => Representative::Point,
                    _ => representative,
                };
                // (every pixel estimated, as the shader does: its largest error decides)
                let errors: Vec<bool> = samples
                    .iter()
                    .chain([nearest])
                    .map(|r| {
                        let sum: f64 = finer
                            .iter()
                            .map(|&f| {
                                luminance(pyramid.node(f).irradiance(
                                    r.0,
                                    r.1,
                                    r_min,
                                    finer_representative,
                                ))
                            })
                            .sum();
                        if criterion != Criterion::Oracle {
                            kernels += 1.0 + finer.len() as f64;
                        }
                        (light(node, r) - sum).abs() > threshold
                    })
                    .collect();
                errors.contains(&true)
            });
        if split {
            frontier.extend(Pyramid::children(at));
        } else {
            list.push(at);
        }
    }
    (list, kernels)
}

/// What a tile gave: its pixels' radiance, and its clusters summed and criterion kernels.
#[derive(Default)]
struct TileResult {
    radiance: Vec<(usize, DVec3)>,
    clusters: f64,
    kernels: f64,
}

/// Sweeps every criterion and representative over one scene.
fn study_scene(
    gpu: &Gpu,
    scene: &Scene,
    size: u32,
    rsm_size: u32,
) -> Result<StudyScene, IndirectError> {
    let mut r = Renderer::new(gpu, scene, Settings::sized(size, size, rsm_size))?;
    r.render_frame(Method::Quadtree)?;
    let side = rsm_size as usize;
    let texels = r.read_nodes()?[..side * side]
        .iter()
        .map(|[flux, pos, normal]| {
            let covered = flux[3] > 0.5;
            let flux = DVec3::new(flux[0].into(), flux[1].into(), flux[2].into());
            let weight = luminance(flux).max(1e-12);
            let position = DVec3::new(pos[0].into(), pos[1].into(), pos[2].into());
            Cluster {
                flux,
                weight,
                mean: position,
                normal_sum: weight
                    * DVec3::new(normal[0].into(), normal[1].into(), normal[2].into()),
                covariance: [0.0; 6],
                // (flux.w: the texel count, 1 where the texel sees geometry)
                lit: covered,
                lo: position,
                hi: position,
            }
        })
        .collect();
    let pyramid = Pyramid::build(texels, side);
    let g_buffer = r.read_receivers()?;
    let truth = brute_force(&r.read_vpls()?, &g_buffer, scene.r_min);
    let v = |a: [f32; 3]| DVec3::new(a[0].into(), a[1].into(), a[2].into());
    let receivers: Vec<Option<Receiver>> = g_buffer
        .iter()
        .map(|g| g.map(|g| (v(g.position), v(g.normal), v(g.albedo))))
        .collect();
    let shaded = receivers.iter().flatten().count().max(1) as f64;
    let (w, h) = (size as usize, size as usize);
    let tiles: Vec<(usize, usize)> = (0..h.div_ceil(TILE))
        .flat_map(|ty| (0..w.div_ceil(TILE)).map(move |tx| (tx, ty)))
        .collect();
    let r_min = f64::from(scene.r_min);
    let mut points = Vec::new();
    for criterion in [
        Criterion::Children,
        Criterion::Grandchildren,
        Criterion::Oracle,
    ] {
        for representative in [Representative::Point, Representative::SecondOrder] {
            for tau in TAUS {
                let setting = (criterion, representative, tau);
                let per_tile: Vec<TileResult> = tiles
                    .par_iter()
                    .map(|&(tx, ty)| {
                        // the tile's covered pixels, and its sample pixels
                        let at = |i: usize| {
                            let (y, x) = (ty * TILE + i / TILE, tx * TILE + i % TILE);
                            (x < w && y < h && receivers[y * w + x].is_some()).then_some(y * w + x)
                        };
                        let pixels: Vec<usize> = (0..TILE_PIXELS).filter_map(at).collect();
                        let covered = std::array::from_fn(|i| at(i).is_some());
                        let samples: Vec<&Receiver> = twin::sample_pixels(&covered)
                            .into_iter()
                            .flatten()
                            .map(|i| receivers[at(i).unwrap()].as_ref().unwrap())
                            .collect();
                        if samples.is_empty() {
                            return TileResult::default();
                        }
                        let tile_receivers: Vec<&Receiver> = pixels
                            .iter()
                            .map(|&p| receivers[p].as_ref().unwrap())
                            .collect();
                        let (cut, kernels) =
                            tile_cut(&pyramid, &tile_receivers, &samples, r_min, setting);
                        let radiance = pixels
                            .iter()
                            .map(|&p| {
                                let (x, n, albedo) = receivers[p].unwrap();
                                let e: DVec3 = cut
                                    .iter()
                                    .map(|&at| {
                                        pyramid.node(at).irradiance(x, n, r_min, representative)
                                    })
                                    .sum();
                                (p, albedo / PI * e)
                            })
                            .collect();
                        TileResult {
                            radiance,
                            clusters: (cut.len() * pixels.len()) as f64,
                            kernels,
                        }
                    })
                    .collect();
                let mut image = vec![[0.0f32; 3]; w * h];
                let (mut cut_sum, mut kernel_sum) = (0.0, 0.0);
                for tile in per_tile {
                    for (p, value) in tile.radiance {
                        image[p] = value.as_vec3().to_array();
                    }
                    cut_sum += tile.clusters;
                    kernel_sum += tile.kernels;
                }
                points.push(StudyPoint {
                    criterion,
                    representative,
                    tau,
                    rel_l1: compare(&image, &truth).rel_l1,
                    cut_per_pixel: cut_sum / shaded,
                    criterion_per_pixel: kernel_sum / shaded,
                });
            }
        }
    }
    Ok(StudyScene {
        scene: scene.name.clone(),
        rsm_size,
        points,
    })
}

/// Runs the study on the `scenes` (file stems; empty: the Cornell box) and writes
/// `cut_study.md`, `cut_study.json` and `cut_study.svg` into `out`.
pub fn run(
    gpu: &Gpu,
    out: &Path,
    size: u32,
    rsm_size: u32,
    scenes: &[String],
    mut progress: impl FnMut(&str),
) -> Result<Vec<StudyScene>, IndirectError> {
    let pairs = u64::from(size).pow(2) * u64::from(rsm_size).pow(2);
    if pairs > MAX_PAIRS {
        return Err(IndirectError::Settings(format!(
            "the cut study sums every VPL at every pixel on the CPU: {size}x{size} pixels x {rsm_size}^2 VPLs is {pairs:.3e} pairs, over the limit of {:.3e}; use a smaller --size or --rsm-size",
            MAX_PAIRS as f64
        )));
    }
    let chosen = if scenes.is_empty() {
        vec!["cornell".to_string()]
    } else {
        scenes.to_vec()
    };
    let mut results = Vec::new();
    for scene in super::equal_error::bundled_scenes(&chosen)? {
        progress(&scene.name);
        results.push(study_scene(gpu, &scene, size, rsm_size)?);
    }
    let mut table = Table::new(
        format!("Per-tile cuts on the CPU: criterion and representative ({size}x{size} image)"),
        &[
            "scene",
            "RSM",
            "criterion",
            "representative",
            "tau",
            "rel L1",
            "clusters/px",
            "criterion kernels/px",
        ],
    );
    let mut series = Vec::new();
    for s in &results {
        for p in &s.points {
            table.row(vec![
                s.scene.clone(),
                format!("{}^2", s.rsm_size),
                format!("{:?}", p.criterion),
                format!("{:?}", p.representative),
                p.tau.to_string(),
                format!("{:.4}", p.rel_l1),
                format!("{:.1}", p.cut_per_pixel),
                format!("{:.1}", p.criterion_per_pixel),
            ]);
        }
        let mut families: Vec<(Criterion, Representative)> = Vec::new();
        for p in &s.points {
            if !families.contains(&(p.criterion, p.representative)) {
                families.push((p.criterion, p.representative));
            }
        }
        for (criterion, representative) in families {
            series.push(Series {
                name: format!("{} {criterion:?}, {representative:?}", s.scene),
                points: s
                    .points
                    .iter()
                    .filter(|p| p.criterion == criterion && p.representative == representative)
                    .map(|p| (p.cut_per_pixel, p.rel_l1))
                    .collect(),
            });
        }
    }
    write_text(&out.join("cut_study.md"), &table.to_markdown())?;
    write_json(&out.join("cut_study.json"), &results)?;
    line_plot(
        &out.join("cut_study.svg"),
        &PlotSpec {
            title: "Per-tile cuts: error against clusters summed (criterion kernels not included)",
            x_label: "clusters summed per shaded pixel",
            y_label: "rel. L1 error of the indirect term",
            log_x: true,
            log_y: true,
        },
        &series,
    )?;
    Ok(results)
}

#[cfg(test)]
mod tests {
    use super::{Cluster, Representative};
    use glam::DVec3;

    /// The second-order term: on a planar 8x8 cluster seen from three receivers it takes most of
    /// the point VPL's error away (a sign or a factor wrong in the Hessian would not).
    #[test]
    fn the_second_order_term_brings_a_cluster_close_to_the_sum_of_its_vpls() {
        let up = DVec3::Y;
        let vpls: Vec<Cluster> = (0..64)
            .map(|i| Cluster {
                flux: DVec3::ONE,
                weight: 1.0,
                mean: DVec3::new(
                    0.3 + 0.01 * (i % 8) as f64,
                    0.0,
                    0.4 + 0.012 * (i / 8) as f64,
                ),
                normal_sum: up,
                covariance: [0.0; 6],
                lit: true,
                lo: DVec3::ZERO,
                hi: DVec3::ZERO,
            })
            .collect();
        let quads: Vec<Cluster> = vpls
            .chunks(4)
            .map(|c| Cluster::joined(&[c[0], c[1], c[2], c[3]]))
            .collect();
        let sixteens: Vec<Cluster> = quads
            .chunks(4)
            .map(|c| Cluster::joined(&[c[0], c[1], c[2], c[3]]))
            .collect();
        let cluster = Cluster::joined(&[sixteens[0], sixteens[1], sixteens[2], sixteens[3]]);
        for (x, n) in [
            (DVec3::new(0.5, 0.3, 0.5), DVec3::NEG_X),
            (DVec3::new(0.4, 0.2, 0.3), DVec3::NEG_Y),
            (
                DVec3::new(0.6, 0.1, 0.45),
                DVec3::new(-0.7, -0.7, 0.1).normalize(),
            ),
        ] {
            let light = |c: &Cluster, r| c.irradiance(x, n, 0.05, r).x;
            let exact: f64 = vpls.iter().map(|v| light(v, Representative::Point)).sum();
            let point = light(&cluster, Representative::Point);
            let second = light(&cluster, Representative::SecondOrder);
            println!("at {x}: exact {exact:.4}, point {point:.4}, second order {second:.4}");
            assert!(
                (second - exact).abs() < 0.2 * (point - exact).abs(),
                "{exact} {point} {second}"
            );
        }
    }
}
