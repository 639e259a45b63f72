//! What every gather pass shares: the bind groups, by how often they change (group 0 per light
//! view, set anew on each light update: the quadtree's settings, the light, the RSM, the quadtree
//! and cut; group 1 per frame:
//! the settings, the camera, the G-buffer and the outputs; group 2 per dispatch: a level and a
//! slice), the buffers behind them, and how a pass makes its shader and pipelines against them.
//! A pass that needs more binds its own groups from 3 on.

use crate::contract::{
    CameraUniform, ClusterUniform, GpuNode, GpuNodeBounds, LevelSlot, LightTermsUniform,
    LightUniform, MAX_SLICES, OCCUPANCY_ROW, Slots, bind_group, compact_constant, compute_pipeline,
    dispatch_2d, layout, pipeline_layout, shader_module, storage_buffer, storage_entry, tex,
    texture_entry, uint_texture_entry, uniform_buffer, uniform_entry, whole,
};
use crate::gathers::samples;
use crate::gbuffer::{GBufferViews, camera_uniform};
use crate::light::node::CutCounts;
use crate::light::quadtree::LightQuadtree;
use crate::light::rsm::{RSM_READ_WGSL, RsmViews};
use crate::light::view::LightView;
use crate::method::GBufferLayout;
use crate::settings::{Settings, Shade};
use crate::shadows::MARCH_WGSL;
use crate::shadows::occupancy::OccupancyGrid;
use crate::wgsl;
use wgpu::util::DeviceExt;

/// What every gather pass's shader starts with (after the prelude): the node layout and kernel,
/// the light, the compact layout's encodings, the receiver, the occupancy walk and the depth-map
/// march of indirect shadows, the RSM's reads, and `shared.wgsl` (the bindings of groups 0-2, the
/// accessors the engine-neutral modules read them with, and the helpers every pass uses).
const SHARED_WGSL: [&str; 9] = [
    wgsl::NODE,
    wgsl::KERNEL,
    wgsl::LIGHT,
    wgsl::COMPACT,
    wgsl::RECEIVER,
    wgsl::OCCUPANCY,
    MARCH_WGSL,
    RSM_READ_WGSL,
    include_str!("shared.wgsl"),
];

/// A gather pass's whole shader: the shared parts, then the pass's `own` in order.
pub(crate) fn shader(own: &[&'static str]) -> Vec<&'static str> {
    SHARED_WGSL.iter().chain(own).copied().collect()
}

/// The per-frame group's buffers: the settings, the camera, the radiance out, the RSM samples,
/// the work counts.
pub(crate) struct Outputs {
    /// The settings (written once) and the camera.
    shade: wgpu::Buffer,
    camera: wgpu::Buffer,
    /// Radiance per pixel, row-major: indirect (rgb, w = 1 where the upsampler recomputed it),
    /// direct (rgb, w = 1 where the G-buffer has geometry), and the low-resolution samples.
    pub indirect: wgpu::Buffer,
    pub direct: wgpu::Buffer,
    low: wgpu::Buffer,
    samples: wgpu::Buffer,
    /// Per pixel: VPL evaluations, texel fetches, bound evaluations and refused splits of the
    /// last indirect passes (four `u32`).
    pub counts: wgpu::Buffer,
    /// The temporal filter's running average of the indirect light (one texel without it).
    pub history: wgpu::Buffer,
    /// The scene's occupancy grid for indirect shadows ([`OccupancyGrid::gpu_words`]).
    occupancy: OccupancyTexture,
}

impl Outputs {
    /// The outputs of a picture of `s` lit through `views` light views.
    fn new(device: &wgpu::Device, s: &Settings, views: usize) -> Self {
        let pixels = u64::from(s.size.width) * u64::from(s.size.height);
        let (lw, lh) = s.low_size();
        let samples = samples::rsm_samples(
            s.samples,
            s.rsm_radius * s.rsm_size as f32 * std::f32::consts::SQRT_2,
            samples::SAMPLE_SEED,
        );
        Self {
            shade: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("shade"),
                contents: bytemuck::bytes_of(&Shade::new(s)),
                usage: wgpu::BufferUsages::UNIFORM,
            }),
            // the picture's size from the start: a caller without indirect shadows may never
            // set the camera
            camera: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("gather camera"),
                contents: bytemuck::bytes_of(&camera_uniform(
                    glam::Mat4::IDENTITY,
                    glam::Vec3::ZERO,
                    (s.size.width, s.size.height),
                )),
                // copied from by the temporal filter, which keeps the view of its history
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_DST
                    | wgpu::BufferUsages::COPY_SRC,
            }),
            indirect: storage_buffer(device, "indirect", pixels * 16),
            direct: storage_buffer(device, "direct", pixels * 16),
            // each view's own samples: the upsampling of one reads them after every view's
            low: storage_buffer(
                device,
                "low-resolution indirect",
                u64::from(lw * lh) * 16 * views as u64,
            ),
            samples: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("rsm samples"),
                contents: bytemuck::cast_slice(&samples),
                usage: wgpu::BufferUsages::STORAGE,
            }),
            counts: storage_buffer(device, "work counts", pixels * 16),
            history: storage_buffer(
                device,
                "indirect history",
                if s.temporal_weight < 1.0 {
                    pixels * 16
                } else {
                    0
                },
            ),
            occupancy: OccupancyTexture::new(device, 0),
        }
    }

    fn frame_group(
        &self,
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        gbuffer: GBufferViews,
    ) -> wgpu::BindGroup {
        let [position, normal, albedo] = gbuffer.textures();
        bind_group(
            device,
            "gather frame",
            layout,
            vec![
                whole(&self.shade),
                whole(&self.camera),
                tex(position),
                tex(normal),
                tex(albedo),
                whole(&self.indirect),
                whole(&self.direct),
                whole(&self.low),
                whole(&self.samples),
                whole(&self.counts),
                whole(&self.history),
                tex(&self.occupancy.view),
            ],
        )
    }
}

/// The occupancy grid's words as the gather reads them: an R32Uint texture of rows of
/// [`OCCUPANCY_ROW`] texels (zero dimensions until a grid is set), and a copy of what it holds,
/// so that a grid updated by what moved is written in the rows that changed, not whole.
pub(crate) struct OccupancyTexture {
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    /// The texture's texels (zeros after the grid's last word).
    held: Vec<u32>,
}

impl OccupancyTexture {
    /// A texture of `rows` rows of zeros.
    fn new(device: &wgpu::Device, rows: u32) -> Self {
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("occupancy grid"),
            size: wgpu::Extent3d {
                width: OCCUPANCY_ROW,
                height: rows.max(1),
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::R32Uint,
            // (read back by the tests)
            usage: wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_DST
                | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        // (wgpu clears a new texture)
        Self {
            view: texture.create_view(&Default::default()),
            held: vec![0; (rows.max(1) * OCCUPANCY_ROW) as usize],
            texture,
        }
    }

    /// Holds `parts`' words, one after the other, from now on: writes the rows from the first
    /// changed word to the last, in the texture there is, or makes a larger one (with an eighth
    /// more rows, for the grid to grow into); whether it made one (the frame's group is then to
    /// be made anew). The words are compared and copied in place, part by part, without being
    /// gathered into one.
    fn write(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, parts: &[&[u32]]) -> bool {
        let row = OCCUPANCY_ROW as usize;
        let len: usize = parts.iter().map(|p| p.len()).sum();
        let made = len > self.held.len();
        if made {
            let rows = len.div_ceil(row) as u32;
            *self = Self::new(device, rows + rows / 8);
        }
        // the first and last word changed, each part's changed words copied in
        let mut changed: Option<(usize, usize)> = None;
        let mut note = |first: usize, last: usize| {
            changed = Some((changed.map_or(first, |c| c.0), last));
        };
        let mut at = 0;
        for &part in parts {
            let held = &mut self.held[at..at + part.len()];
            if held != part {
                let differs = |(h, w): (&u32, &u32)| h != w;
                let first = held
                    .iter()
                    .zip(part)
                    .position(differs)
                    .expect("they differ");
                let last = held
                    .iter()
                    .zip(part)
                    .rposition(differs)
                    .expect("they differ");
                held[first..=last].copy_from_slice(&part[first..=last]);
                note(at + first, at + last);
            }
            at += part.len();
        }
        // zeros after the last word, where a longer grid's words were
        let tail = &mut self.held[at..];
        if let Some(first) = tail.iter().position(|&w| w != 0) {
            let last = tail.iter().rposition(|&w| w != 0).expect("one is not zero");
            tail[first..=last].fill(0);
            note(at + first, at + last);
        }
        let Some((first, last)) = changed else {
            return made;
        };
        let (first_row, end_row) = (first / row, last / row + 1);
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &self.texture,
                mip_level: 0,
                origin: wgpu::Origin3d {
                    x: 0,
                    y: first_row as u32,
                    z: 0,
                },
                aspect: wgpu::TextureAspect::All,
            },
            bytemuck::cast_slice(&self.held[first_row * row..end_row * row]),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(OCCUPANCY_ROW * 4),
                rows_per_image: None,
            },
            wgpu::Extent3d {
                width: OCCUPANCY_ROW,
                height: (end_row - first_row) as u32,
                depth_or_array_layers: 1,
            },
        );
        made
    }
}

/// One light view's maps as the gather reads them: its RSM and the light quadtree built from it.
#[derive(Clone, Copy)]
pub struct ViewMaps<'a> {
    /// The view's RSM.
    pub rsm: RsmViews<'a>,
    /// The quadtree built from it.
    pub quadtree: &'a LightQuadtree,
}

/// One light view's group 0: the light, the gather's terms of it, and its bind group.
struct ViewGroup {
    light: wgpu::Buffer,
    terms: wgpu::Buffer,
    group: wgpu::BindGroup,
}

impl ViewGroup {
    fn new(device: &wgpu::Device, layout: &wgpu::BindGroupLayout, maps: ViewMaps) -> Self {
        let light = uniform_buffer::<LightUniform>(device, "gather light");
        // storage, not uniform: see shared.wgsl
        let terms = storage_buffer(
            device,
            "gather light terms",
            size_of::<LightTermsUniform>() as u64,
        );
        Self {
            group: light_group(device, layout, [&light, &terms], maps),
            light,
            terms,
        }
    }
}

/// The shared groups' layouts, buffers and bind groups, at one set of sizes.
pub(crate) struct Resources {
    settings: Settings,
    /// The layouts of the G-buffer and of the RSMs the pipelines read.
    gbuffer_layout: GBufferLayout,
    rsm_layout: GBufferLayout,
    light_layout: wgpu::BindGroupLayout,
    frame_layout: wgpu::BindGroupLayout,
    dispatch_layout: wgpu::BindGroupLayout,
    /// Per light view: the light, the gather's terms of it, the maps.
    views: Vec<ViewGroup>,
    pub outputs: Outputs,
    slots: Slots,
    frame_group: wgpu::BindGroup,
    dispatch_group: wgpu::BindGroup,
}

impl Resources {
    /// The shared resources of a gather of `settings` (checked) reading the light views' `maps`
    /// (at least one, all in one layout) and the caller's G-buffer.
    pub fn new(
        device: &wgpu::Device,
        settings: &Settings,
        maps: &[ViewMaps],
        gbuffer: GBufferViews,
    ) -> Self {
        let s = settings;
        let rsm_layout = maps[0].rsm.layout();
        let compute = wgpu::ShaderStages::COMPUTE;
        let light_layout = layout(
            device,
            "gather light",
            &[
                uniform_entry::<ClusterUniform>(0, compute, false),
                uniform_entry::<LightUniform>(1, compute, false),
                storage_entry::<LightTermsUniform>(2, true),
                texture_entry(3),
                texture_entry(4),
                texture_entry(5),
                storage_entry::<GpuNode>(6, true),
                storage_entry::<GpuNode>(7, true),
                storage_entry::<CutCounts>(8, true),
                storage_entry::<GpuNodeBounds>(9, true),
            ],
        );
        let frame_layout = layout(
            device,
            "gather frame",
            &[
                uniform_entry::<Shade>(0, compute, false),
                storage_entry::<CameraUniform>(1, true),
                texture_entry(2),
                texture_entry(3),
                texture_entry(4),
                storage_entry::<[f32; 4]>(5, false),
                storage_entry::<[f32; 4]>(6, false),
                storage_entry::<[f32; 4]>(7, false),
                storage_entry::<[f32; 4]>(8, true),
                storage_entry::<[u32; 4]>(9, false),
                storage_entry::<[f32; 4]>(10, false),
                uint_texture_entry(11),
            ],
        );
        let dispatch_layout = layout(
            device,
            "gather dispatch",
            &[
                uniform_entry::<LevelSlot>(0, compute, true),
                uniform_entry::<LevelSlot>(1, compute, true),
            ],
        );
        let slots = Slots::new(device, "gather slots", MAX_SLICES);
        let dispatch_group = bind_group(
            device,
            "gather dispatch",
            &dispatch_layout,
            vec![slots.binding(), slots.binding()],
        );
        let views = maps
            .iter()
            .map(|&m| ViewGroup::new(device, &light_layout, m))
            .collect();
        let outputs = Outputs::new(device, s, maps.len());
        Self {
            settings: s.clone(),
            gbuffer_layout: gbuffer.layout(),
            rsm_layout,
            views,
            frame_group: outputs.frame_group(device, &frame_layout, gbuffer),
            outputs,
            slots,
            dispatch_group,
            light_layout,
            frame_layout,
            dispatch_layout,
        }
    }

    /// The settings the gather was built with.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// How many light views the gather sums.
    pub fn view_count(&self) -> usize {
        self.views.len()
    }

    /// Reads other quadtrees or RSMs from now on (as many as before, in the same layout).
    pub fn bind_maps(&mut self, device: &wgpu::Device, maps: &[ViewMaps]) {
        assert_eq!(maps.len(), self.views.len(), "one maps a light view");
        for m in maps {
            assert_eq!(
                m.rsm.layout(),
                self.rsm_layout,
                "the RSMs keep their layout"
            );
        }
        for (view, &m) in self.views.iter_mut().zip(maps) {
            view.group = light_group(device, &self.light_layout, [&view.light, &view.terms], m);
        }
    }

    /// Shades another G-buffer of the same size and layout from now on.
    pub fn bind_gbuffer(&mut self, device: &wgpu::Device, gbuffer: GBufferViews) {
        assert_eq!(
            gbuffer.layout(),
            self.gbuffer_layout,
            "the G-buffer keeps its layout"
        );
        self.frame_group = self
            .outputs
            .frame_group(device, &self.frame_layout, gbuffer);
    }

    /// Walks `grid` for indirect shadows from now on: the rows of its words that changed
    /// since the last grid are written (the frame's group is made anew, with the G-buffer's
    /// views, only where the grid outgrew its texture).
    pub fn set_occupancy(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        grid: &OccupancyGrid,
        gbuffer: GBufferViews,
    ) {
        let (header, [bits, first, masks]) = grid.gpu_word_parts();
        let parts = [&header[..], bits, first, masks];
        if self.outputs.occupancy.write(device, queue, &parts) {
            self.bind_gbuffer(device, gbuffer);
        }
    }

    /// Writes the light views and the gather's terms of them (the kernel's clamp `r_min`, world
    /// units), one a view.
    pub fn set_lights(&self, queue: &wgpu::Queue, lights: &[LightView], r_min: f32) {
        assert_eq!(lights.len(), self.views.len(), "one light view a view");
        let low_samples = {
            let (w, h) = self.settings.low_size();
            w * h
        };
        for (i, (view, light)) in self.views.iter().zip(lights).enumerate() {
            let uniform = light.uniform(self.settings.rsm_size);
            queue.write_buffer(&view.light, 0, bytemuck::bytes_of(&uniform));
            let terms = light.terms(&self.settings, r_min, i as u32 * low_samples);
            queue.write_buffer(&view.terms, 0, bytemuck::bytes_of(&terms));
        }
    }

    /// Writes the camera the G-buffer is rendered from.
    pub fn set_camera(&self, queue: &wgpu::Queue, view_proj: glam::Mat4, eye: glam::Vec3) {
        let s = &self.settings;
        let camera = camera_uniform(view_proj, eye, (s.size.width, s.size.height));
        queue.write_buffer(&self.outputs.camera, 0, bytemuck::bytes_of(&camera));
    }

    /// A pass's pipelines, one per entry point of its shader ([`shader`] of `own`), whose layout
    /// is the shared groups then `own_groups` (from group 3 on).
    pub fn pipelines<const N: usize>(
        &self,
        device: &wgpu::Device,
        label: &str,
        own: &[&'static str],
        entries: [&str; N],
        own_groups: &[&wgpu::BindGroupLayout],
    ) -> [wgpu::ComputePipeline; N] {
        let module = shader_module(device, label, &shader(own));
        let groups: Vec<&wgpu::BindGroupLayout> = [
            &self.light_layout,
            &self.frame_layout,
            &self.dispatch_layout,
        ]
        .into_iter()
        .chain(own_groups.iter().copied())
        .collect();
        let layout = pipeline_layout(device, &groups);
        // the pipeline constants of shared.wgsl and light/rsm_read.wgsl
        let constants = [
            (
                "SHADOWS",
                f64::from(u8::from(self.settings.march_steps() > 0)),
            ),
            compact_constant("COMPACT_GBUFFER", self.gbuffer_layout),
            compact_constant("COMPACT_RSM", self.rsm_layout),
        ];
        entries.map(|entry| compute_pipeline(device, &layout, &module, entry, &constants))
    }

    /// Binds light view `view`'s group and the frame's.
    pub fn bind_groups(&self, pass: &mut wgpu::ComputePass, view: usize) {
        pass.set_bind_group(0, &self.views[view].group, &[]);
        pass.set_bind_group(1, &self.frame_group, &[]);
    }

    /// Binds the dispatch group: `level` and `slice`.
    pub fn bind_dispatch(&self, pass: &mut wgpu::ComputePass, level: u32, slice: u32) {
        pass.set_bind_group(
            2,
            &self.dispatch_group,
            &[self.slots.offset(level), self.slots.offset(slice)],
        );
    }

    /// A per-pixel sum over `width` x `height` pixels in `count` slices (the first writes, the
    /// others add), at `level`, with the pipeline set.
    pub fn sliced(
        &self,
        pass: &mut wgpu::ComputePass,
        level: u32,
        count: u32,
        (width, height): (u32, u32),
    ) {
        for slice in 0..count {
            self.bind_dispatch(pass, level, slice);
            dispatch_2d(pass, width, height);
        }
    }

    /// The camera uniform (world -> clip first).
    pub fn camera(&self) -> &wgpu::Buffer {
        &self.outputs.camera
    }

    /// The picture's size in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.settings.size.width, self.settings.size.height)
    }
}

/// A light view's group: its quadtree's settings, the light and its terms, the RSM, the
/// quadtree's nodes, cut and bounds.
fn light_group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    [light, terms]: [&wgpu::Buffer; 2],
    ViewMaps { rsm, quadtree }: ViewMaps,
) -> wgpu::BindGroup {
    let [flux, position, normal] = rsm.textures();
    bind_group(
        device,
        "gather light",
        layout,
        vec![
            whole(quadtree.params()),
            whole(light),
            whole(terms),
            tex(flux),
            tex(position),
            tex(normal),
            whole(quadtree.nodes()),
            whole(quadtree.cut()),
            whole(quadtree.cut_count()),
            whole(quadtree.bounds()),
        ],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The texture's texels as words.
    fn texels(gpu: &quadray_gpu::Gpu, occupancy: &OccupancyTexture) -> Vec<u32> {
        let read = quadray_gpu::read_texture_f32(gpu, &occupancy.texture, 0, 1);
        bytemuck::cast_slice(&read.expect("read back")).to_vec()
    }

    #[test]
    fn a_grid_written_in_its_changed_rows_reads_as_one_written_whole() {
        let gpu = quadray_gpu::Gpu::new().expect("an adapter (run scripts/setup.sh for lavapipe)");
        let (d, q) = (&gpu.device, &gpu.queue);
        let row = OCCUPANCY_ROW as usize;
        let first: Vec<u32> = (1..=5 * row as u32 / 2).collect();
        let mut occupancy = OccupancyTexture::new(d, 0);
        assert!(
            occupancy.write(d, q, &[&first]),
            "a grid larger than the texture"
        );
        // two words changed a row apart, and the last half row gone: rows 1 to 2 written
        let mut shorter = first[..2 * row + 50].to_vec();
        shorter[row + 3] = 0xdead;
        shorter[2 * row + 7] = 0xbeef;
        // and then one that outgrows the texture
        let rows = occupancy.held.len() / row;
        let longer: Vec<u32> = (0..(rows * row + 3) as u32).map(|i| i * 7).collect();
        for (words, made) in [(&shorter, false), (&first, false), (&longer, true)] {
            // in two parts, split between the changed words (as a grid's bits and masks are)
            let (a, b) = words.split_at(row + 5);
            assert_eq!(occupancy.write(d, q, &[a, b]), made);
            let mut expected = words.clone();
            expected.resize(occupancy.held.len(), 0);
            assert_eq!(texels(&gpu, &occupancy), expected);
        }
    }
}
