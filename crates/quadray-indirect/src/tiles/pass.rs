//! Per-tile cuts ([`Method::QuadtreeTiles`]): one workgroup a tile of 8x8 pixels refines
//! its own cut of the light quadtree against a bound of each node's contribution, then its pixels
//! sum it, and the light's steps at the tiles' boundaries are smoothed where the pixels lie on
//! one surface (`deblock.wgsl`). With indirect shadows and [`TilePasses::Split`] the kernel runs
//! as three dispatches (`split.wgsl`): the lists, the shadow walks, the sums. The tiles' lists
//! are this pass's own group 3.

use crate::contract::{bind_group, dispatch_2d, layout, storage_buffer, storage_entry, whole};
use crate::gathers::resources::Resources;
use crate::wgsl;
#[cfg(doc)]
use crate::{Method, TilePasses};
use std::sync::OnceLock;

/// The fused kernel's shader parts, after the shared ones ([`TilePasses::Fused`]).
pub(crate) const WGSL: [&str; 6] = [
    wgsl::BOUND,
    wgsl::TILE_RULE,
    include_str!("kernel.wgsl"),
    include_str!("anchors.wgsl"),
    include_str!("deblock.wgsl"),
    include_str!("fused.wgsl"),
];

/// The split passes' shader parts ([`TilePasses::Split`]): the same phases, their own entry
/// points and accessors.
pub(crate) const SPLIT_WGSL: [&str; 6] = [
    wgsl::BOUND,
    wgsl::TILE_RULE,
    include_str!("kernel.wgsl"),
    include_str!("anchors.wgsl"),
    include_str!("deblock.wgsl"),
    include_str!("split.wgsl"),
];

/// The per-tile cuts' lists and their bind group (group 3).
struct TileLists {
    /// Per tile, the per-tile cut's entries (`tile_capacity` slots a tile): a node's index in
    /// the low [`super::TILE_ENTRY_INDEX_BITS`], with indirect shadows its visibility
    /// target's slot above.
    cuts: wgpu::Buffer,
    /// Per tile, the nodes its list holds, the splits refused for want of room, the nodes whose
    /// error it estimated and the VPL evaluations that took (four `u32`).
    sizes: wgpu::Buffer,
    /// With indirect shadows, per tile the nodes its shadow rays go to (`tile_capacity` slots a
    /// tile; one word without shadows). Only the shader reads it.
    _targets: wgpu::Buffer,
    /// The split passes' shadow records ([`crate::Settings::tile_shadow_bytes`]), none when
    /// fused. Only the shaders read them.
    _shadows: Option<wgpu::Buffer>,
    group: wgpu::BindGroup,
}

/// The per-tile kernel's pipelines.
enum Kernel {
    /// One dispatch a light view.
    Fused(wgpu::ComputePipeline),
    /// Three: the lists, the shadow walks, the sums.
    Split([wgpu::ComputePipeline; 3]),
}

pub(crate) struct Tiles {
    kernel: Kernel,
    /// The deblocking filter across the columns' boundaries, then across the rows'.
    deblock: [wgpu::ComputePipeline; 2],
    lists_layout: wgpu::BindGroupLayout,
    /// Allocated by the first frame (up to [`crate::Settings::MAX_TILE_LIST_BYTES`]), so that
    /// the other methods pay nothing for them.
    lists: OnceLock<TileLists>,
    /// To allocate the lists when first drawn.
    device: wgpu::Device,
}

impl Tiles {
    pub fn new(device: &wgpu::Device, res: &Resources) -> Self {
        let split = res.settings().splits_tiles();
        let mut entries = vec![
            storage_entry::<u32>(0, false),
            storage_entry::<[u32; 4]>(1, false),
            storage_entry::<u32>(2, false),
        ];
        if split {
            entries.push(storage_entry::<u32>(3, false));
        }
        let lists_layout = layout(device, "per-tile cuts", &entries);
        let layouts = [&lists_layout];
        let deblock = ["deblock_columns", "deblock_rows"];
        let (kernel, columns, rows) = if split {
            let [lists, walks, sums, columns, rows] = res.pipelines(
                device,
                "gather tiles split",
                &SPLIT_WGSL,
                [
                    "tile_lists",
                    "tile_walks",
                    "tile_sums",
                    deblock[0],
                    deblock[1],
                ],
                &layouts,
            );
            (Kernel::Split([lists, walks, sums]), columns, rows)
        } else {
            let [kernel, columns, rows] = res.pipelines(
                device,
                "gather tiles",
                &WGSL,
                ["indirect_tiles", deblock[0], deblock[1]],
                &layouts,
            );
            (Kernel::Fused(kernel), columns, rows)
        };
        Self {
            kernel,
            deblock: [columns, rows],
            lists_layout,
            lists: OnceLock::new(),
            device: device.clone(),
        }
    }

    /// Records one workgroup a tile (a list of at most `TILE_FRONTIER` nodes fits a slice), the
    /// lists allocated first; split, the lists', the walks' and the sums' dispatches in turn.
    pub fn record(&self, pass: &mut wgpu::ComputePass, res: &Resources) {
        let s = res.settings();
        let (tx, ty) = s.tiles();
        let lists = self.lists.get_or_init(|| {
            let cuts = storage_buffer(&self.device, "per-tile cuts", s.tile_list_bytes());
            let tiles = u64::from(tx) * u64::from(ty);
            let sizes = storage_buffer(&self.device, "per-tile cut sizes", tiles * 16);
            let target_bytes = if s.march_steps() > 0 {
                s.tile_list_bytes()
            } else {
                4
            };
            let targets = storage_buffer(&self.device, "per-tile shadow targets", target_bytes);
            let shadows = matches!(self.kernel, Kernel::Split(_)).then(|| {
                let bytes = s.tile_shadow_bytes();
                storage_buffer(&self.device, "per-tile shadow records", bytes)
            });
            let mut buffers = vec![whole(&cuts), whole(&sizes), whole(&targets)];
            buffers.extend(shadows.as_ref().map(whole));
            let group = bind_group(&self.device, "per-tile cuts", &self.lists_layout, buffers);
            TileLists {
                cuts,
                sizes,
                _targets: targets,
                _shadows: shadows,
                group,
            }
        });
        pass.set_bind_group(3, &lists.group, &[]);
        res.bind_dispatch(pass, 0, 0);
        match &self.kernel {
            Kernel::Fused(kernel) => {
                pass.set_pipeline(kernel);
                pass.dispatch_workgroups(tx, ty, 1);
            }
            Kernel::Split([lists, walks, sums]) => {
                pass.set_pipeline(lists);
                pass.dispatch_workgroups(tx, ty, 1);
                pass.set_pipeline(walks);
                pass.dispatch_workgroups(tx.div_ceil(64 / res.settings().tile_walk_lanes), ty, 1);
                pass.set_pipeline(sums);
                pass.dispatch_workgroups(tx, ty, 1);
            }
        }
    }

    /// Records the deblocking filter over the light every view's tiles summed, where
    /// [`crate::Settings::tile_deblock`] asks for it: one invocation a boundary and line of
    /// pixels, the columns' boundaries first. Needs the lists' group that [`Tiles::record`] set.
    pub fn record_deblock(&self, pass: &mut wgpu::ComputePass, res: &Resources) {
        let s = res.settings();
        if s.tile_deblock == 0 {
            return;
        }
        let (tx, ty) = s.tiles();
        res.bind_dispatch(pass, 0, 0);
        let lines = [(tx - 1, s.size.height), (ty - 1, s.size.width)];
        for (pipeline, (boundaries, lines)) in self.deblock.iter().zip(lines) {
            if boundaries > 0 {
                pass.set_pipeline(pipeline);
                dispatch_2d(pass, boundaries, lines);
            }
        }
    }

    /// The last per-tile cuts, `None` before the first frame: per tile, its node indices
    /// (`tile_capacity` `u32` slots a tile), and its list's length, refused splits, nodes
    /// estimated and the estimates' VPL evaluations (`[u32; 4]`).
    pub fn lists(&self) -> Option<(&wgpu::Buffer, &wgpu::Buffer)> {
        self.lists.get().map(|t| (&t.cuts, &t.sizes))
    }
}
