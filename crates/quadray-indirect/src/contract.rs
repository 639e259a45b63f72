//! The Rust side of the Rust <-> WGSL contract: the structs the shaders share, each declared
//! once with [`shader_struct!`] (`#[repr(C)]`, `Pod`; layout entries carry their
//! `min_binding_size`), the WGSL prelude generated here from the Rust constants and those
//! structs and put in front of every shader, and the helpers the passes build their layouts,
//! buffers and pipelines with. A test parses every shader with naga and holds each shared
//! struct's size and field offsets against these.

use crate::light::node::{CONE_SLACK, CUT_CLASS_SIDE, EMPTY_BOX, MAX_LEVELS};
use crate::method::GBufferLayout;
use crate::reference::LUMINANCE;
use crate::settings::{Shade, TILE, TILE_FRONTIER, TILE_SHADOW_HEADER};
use crate::shader_struct::{Layout, shader_struct};
use crate::shadows::occupancy::{
    BRICK, END_CLEARANCE_CELLS, END_OFFSET_CELLS, HEADER_WORDS, SUBCELLS,
};
use crate::tiles::deblock::{
    ALBEDO as DEBLOCK_ALBEDO, LIMIT as DEBLOCK_LIMIT, PLANE as DEBLOCK_PLANE,
};
use crate::tiles::{
    MIXED_TARGET_ANGLE, MOST_WALKED_TILES, NEAR_FIELD_SIZE, PARALLEL_TARGET_COS, SPLIT_BINS,
    TILE_ENTRY_INDEX_BITS, ZERO_ESTIMATE_SHARE,
};
use wgpu::util::DeviceExt;

/// Items (VPLs, clusters, samples) one dispatch of a per-pixel sum covers; longer sums take
/// several dispatches that add up. lavapipe (llvmpipe) silently ends an invocation's loops after
/// 65,535 iterations in all, which cut a 512^2 brute force to the RSM's top rows, and an item
/// counts more than once where loops are nested in the sum's body (the visibility test's two,
/// even where they do not run: at 32,768 items the cut's sum over a million clusters stopped at
/// two thirds); on a GPU it keeps each dispatch short.
pub(crate) const SLICE: u32 = 16384;
/// Nodes one dispatch of a per-level pass covers: each node's cut test climbs up to 10
/// ancestors, so fewer nodes keep it under lavapipe's limit too.
pub(crate) const LEVEL_SLICE: u32 = 2048;
/// Slice uniform slots: enough for level 0 of a 1024^2 RSM in level slices, the longest sum.
pub(crate) const MAX_SLICES: u32 = 1024 * 1024 / LEVEL_SLICE;

/// Which light the output pass writes (its values are WGSL constants of the prelude).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum OutputTerm {
    /// The one-bounce indirect light alone (to add to the caller's own direct light).
    Indirect = 0,
    /// The lights' direct light, shadowed by their shadow maps.
    Direct = 1,
    /// Direct plus indirect: what `quadray indirect` pictures.
    Combined = 2,
}

/// What every shader starts with, generated from Rust: the constants and the shared structs.
pub(crate) fn prelude() -> String {
    format!(
        "// Generated from contract.rs: do not repeat these by hand.\n\
         const SLICE: u32 = {SLICE}u;\n\
         const LEVEL_SLICE: u32 = {LEVEL_SLICE}u;\n\
         const MAX_LEVELS: u32 = {MAX_LEVELS}u;\n\
         const TILE_FRONTIER: u32 = {TILE_FRONTIER}u;\n\
         const TILE_ENTRY_INDEX_BITS: u32 = {TILE_ENTRY_INDEX_BITS}u;\n\
         const TILE_SHADOW_HEADER: u32 = {TILE_SHADOW_HEADER}u;\n\
         const MOST_WALKED_TILES: u32 = {MOST_WALKED_TILES}u;\n\
         const TILE: u32 = {TILE}u;\n\
         const NEAR_FIELD_SIZE: f32 = {NEAR_FIELD_SIZE:?};\n\
         const EMPTY_BOX: f32 = {EMPTY_BOX:?};\n\
         const CONE_SLACK: f32 = {CONE_SLACK:?};\n\
         const SPLIT_BINS: u32 = {SPLIT_BINS}u;\n\
         const MIXED_TARGET_ANGLE: f32 = {MIXED_TARGET_ANGLE:?};\n\
         const PARALLEL_TARGET_COS: f32 = {PARALLEL_TARGET_COS:?};\n\
         const ZERO_ESTIMATE_SHARE: f32 = {ZERO_ESTIMATE_SHARE:?};\n\
         const PI: f32 = {:?};\n\
         const OUTPUT_INDIRECT: u32 = {}u;\n\
         const OUTPUT_DIRECT: u32 = {}u;\n\
         const OUTPUT_COMBINED: u32 = {}u;\n\
         const OCCUPANCY_ROW: u32 = {OCCUPANCY_ROW}u;\n\
         const OCCUPANCY_HEADER: u32 = {}u;\n\
         const OCCUPANCY_END_OFFSET: f32 = {END_OFFSET_CELLS:?};\n\
         const OCCUPANCY_END_CLEARANCE: f32 = {END_CLEARANCE_CELLS:?};\n\
         const OCCUPANCY_BRICK = vec3<u32>({}u, {}u, {}u);\n\
         const OCCUPANCY_SUBCELLS: u32 = {SUBCELLS}u;\n\
         const DEBLOCK_LIMIT: f32 = {DEBLOCK_LIMIT:?};\n\
         const DEBLOCK_PLANE: f32 = {DEBLOCK_PLANE:?};\n\
         const DEBLOCK_ALBEDO: f32 = {DEBLOCK_ALBEDO:?};\n\
         const MAX_INTERLEAVE: u32 = {}u;\n\
         const CUT_CLASS_SIDE: u32 = {CUT_CLASS_SIDE}u;\n\
         const SHADOW_CORNER_WORDS: u32 = {}u;\n\
         const LUMINANCE = vec3<f32>({:?}, {:?}, {:?});\n",
        std::f32::consts::PI,
        OutputTerm::Indirect as u32,
        OutputTerm::Direct as u32,
        OutputTerm::Combined as u32,
        HEADER_WORDS,
        BRICK.x,
        BRICK.y,
        BRICK.z,
        crate::Settings::INTERLEAVE.max,
        crate::Settings::SHADOW_CORNER_CLUSTERS / 32,
        LUMINANCE[0] as f32,
        LUMINANCE[1] as f32,
        LUMINANCE[2] as f32,
    ) + &shared_structs()
        .into_iter()
        .map(|s| s.wgsl)
        .collect::<String>()
}

/// Texels a row of the occupancy grid's texture (`OCCUPANCY_ROW`): a texture, not a storage
/// buffer, as the most demanding gather pass binds as many storage buffers as it may.
pub(crate) const OCCUPANCY_ROW: u32 = 1024;

/// A shader's whole source: the prelude, then `parts` in order.
pub(crate) fn shader_source(parts: &[&str]) -> String {
    std::iter::once(prelude().as_str())
        .chain(parts.iter().copied())
        .collect()
}

pub(crate) fn shader_module(
    device: &wgpu::Device,
    label: &str,
    parts: &[&str],
) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(shader_source(parts).into()),
    })
}

shader_struct! {
    /// One RSM view of a light (a spot, a point light's cube face, the sun), written with the
    /// light.
    pub(crate) struct LightUniform as "Light" {
        view_proj: [[f32; 4]; 4],
        /// Clip -> world relative to `position`: a compact RSM's positions are rebuilt from its
        /// depth (relative, so that the translation does not cancel out in f32).
        inv_view_proj: [[f32; 4]; 4],
        /// xyz: position (the sun: the middle of the map's near plane), w: 1 / scene extent (the
        /// RSM's depth unit).
        position: [f32; 4],
        /// xyz: unit axis, w: cos(cone) (-1: no cone).
        direction: [f32; 4],
        /// rgb: intensity (a spot's on its axis; the sun: irradiance facing it), w:
        /// cos(cone - falloff).
        intensity: [f32; 4],
        /// x: 1 for parallel light (the sun, an orthographic map), 0 from a point; y: an RSM
        /// texel's measure on the axis, its solid angle (it shrinks as cos^3 off the axis) or its
        /// area across parallel light.
        parallel: [f32; 4],
    }
}

shader_struct! {
    /// A raster pass's projection (the RSM from the light, the camera's G-buffer).
    pub(crate) struct RasterUniform as "Raster" {
        view_proj: [[f32; 4]; 4],
        /// The camera's position for the G-buffer (normals are turned towards the viewer).
        eye: [f32; 4],
    }
}

shader_struct! {
    /// One light view's shadow map for the direct light (the sun's fitted to the camera's view, a
    /// spot's or a cube face's the RSM's view), written with the light and the camera.
    pub(crate) struct ShadowUniform as "Shadow" {
        /// World -> the shadow map's clip space.
        view_proj: [[f32; 4]; 4],
        /// x: a texel's side in world units (parallel light), or at unit distance along the
        /// axis (from a point); y: 1 for parallel light; z: the map's side in texels.
        texel: [f32; 4],
    }
}

shader_struct! {
    /// The light quadtree's settings.
    pub(crate) struct ClusterUniform as "ClusterParams" {
        rsm_size: u32,
        /// Number of levels: log2(rsm_size) + 1.
        levels: u32,
        start_level: u32,
        limit_level: u32,
        recursive: u32,
        flux_weighted: u32,
        depth_threshold: f32,
        normal_threshold: f32,
    }
}

shader_struct! {
    /// The gather's per-view values, written with the light.
    pub(crate) struct LightTermsUniform as "LightTerms" {
        /// The clamp of the VPL kernel's 1/r^4 (world units).
        r_min: f32,
        /// Geometry agreement for upsampling: plane distance (world units).
        plane_agreement: f32,
        /// Indirect shadows: how deep behind a depth map's surface a point counts as inside the
        /// occluder (world units).
        shadow_thickness: f32,
        /// Where this view's low-resolution samples start; 0 for a frame's first light view,
        /// which writes the radiance the others add to.
        low_offset: u32,
    }
}

shader_struct! {
    /// The gather's per-camera values (the G-buffer's view and size), written with the camera.
    pub(crate) struct CameraUniform as "Camera" {
        view_proj: [[f32; 4]; 4],
        /// Clip -> world relative to `eye`: a compact G-buffer's positions are rebuilt from its
        /// depth (relative, so that the translation does not cancel out in f32).
        inv_view_proj: [[f32; 4]; 4],
        eye: [f32; 4],
        width: u32,
        height: u32,
        /// Up to the struct's 16-byte alignment.
        _pad: [u32; 2],
    }
}

shader_struct! {
    /// One slot of the per-dispatch uniforms (a level, or a slice of a long sum).
    pub(crate) struct LevelSlot as "Level" {
        level: u32,
    }
}

shader_struct! {
    /// One cluster of the light quadtree (a level-0 node is one RSM texel, one VPL).
    pub(crate) struct GpuNode as "Node" {
        /// rgb: summed flux, w: number of texels that see geometry.
        flux: [f32; 4],
        /// xyz: mean position, w: mean RSM depth (light-axis distance / scene extent).
        pos: [f32; 4],
        /// xyz: renormalised mean normal, w: 1 when the cluster is valid.
        normal: [f32; 4],
    }
}

shader_struct! {
    /// What bounds a node's contribution (per-tile cuts): the box of its VPLs' positions and a
    /// cone holding their normals (axis: the node's mean normal). Empty nodes hold an empty box
    /// (lo > hi).
    pub(crate) struct GpuNodeBounds as "NodeBounds" {
        /// xyz: the box's low corner; w: cosine of the normal cone's half-angle.
        lo: [f32; 4],
        /// xyz: the box's high corner.
        hi: [f32; 4],
    }
}

/// Every struct shared with WGSL, each declared once (here, or with what it holds: the gather's
/// settings in `settings.rs`): the prelude declares them for every shader, the contract test
/// holds each layout to naga's.
pub(crate) fn shared_structs() -> Vec<Layout> {
    vec![
        Layout::of::<LightUniform>(),
        Layout::of::<RasterUniform>(),
        Layout::of::<ShadowUniform>(),
        Layout::of::<ClusterUniform>(),
        Layout::of::<Shade>(),
        Layout::of::<LightTermsUniform>(),
        Layout::of::<CameraUniform>(),
        Layout::of::<LevelSlot>(),
        Layout::of::<GpuNode>(),
        Layout::of::<GpuNodeBounds>(),
    ]
}

fn min_size<T>() -> Option<wgpu::BufferSize> {
    wgpu::BufferSize::new(size_of::<T>() as u64)
}

/// A uniform holding a `T`.
pub(crate) fn uniform_entry<T>(
    binding: u32,
    visibility: wgpu::ShaderStages,
    dynamic: bool,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: dynamic,
            min_binding_size: min_size::<T>(),
        },
        count: None,
    }
}

/// A storage buffer of `T`s (at least one).
pub(crate) fn storage_entry<T>(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: min_size::<T>(),
        },
        count: None,
    }
}

/// A float texture read with `textureLoad` (any float format: no filtering).
pub(crate) fn texture_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

/// An unsigned integer texture read with `textureLoad`.
pub(crate) fn uint_texture_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Uint,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

pub(crate) fn uniform_buffer<T>(device: &wgpu::Device, label: &str) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size_of::<T>() as u64,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

pub(crate) fn storage_buffer(device: &wgpu::Device, label: &str, size: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16),
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// Uniform slots holding 0, 1, 2, ... `count - 1`, one bound per dispatch with a dynamic offset
/// (a multiple of the returned stride).
pub(crate) struct Slots {
    pub buffer: wgpu::Buffer,
    pub stride: u32,
}

impl Slots {
    pub fn new(device: &wgpu::Device, label: &str, count: u32) -> Self {
        let stride = device.limits().min_uniform_buffer_offset_alignment.max(16);
        let contents: Vec<u8> = (0..count)
            .flat_map(|i| {
                let mut slot = vec![0u8; stride as usize];
                slot[..4].copy_from_slice(&i.to_le_bytes());
                slot
            })
            .collect();
        let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: &contents,
            usage: wgpu::BufferUsages::UNIFORM,
        });
        Self { buffer, stride }
    }

    /// The binding of one slot (the dynamic offset picks which).
    pub fn binding(&self) -> wgpu::BindingResource<'_> {
        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &self.buffer,
            offset: 0,
            size: wgpu::BufferSize::new(16),
        })
    }

    pub fn offset(&self, index: u32) -> u32 {
        index * self.stride
    }
}

/// Bind group entries numbered from 0 in the order given.
pub(crate) fn entries(list: Vec<wgpu::BindingResource<'_>>) -> Vec<wgpu::BindGroupEntry<'_>> {
    list.into_iter()
        .enumerate()
        .map(|(i, resource)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource,
        })
        .collect()
}

pub(crate) fn bind_group(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    list: Vec<wgpu::BindingResource<'_>>,
) -> wgpu::BindGroup {
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries(list),
    })
}

pub(crate) fn layout(
    device: &wgpu::Device,
    label: &str,
    entries: &[wgpu::BindGroupLayoutEntry],
) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries,
    })
}

pub(crate) fn pipeline_layout(
    device: &wgpu::Device,
    groups: &[&wgpu::BindGroupLayout],
) -> wgpu::PipelineLayout {
    let groups: Vec<Option<&wgpu::BindGroupLayout>> = groups.iter().copied().map(Some).collect();
    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: None,
        bind_group_layouts: &groups,
        immediate_size: 0,
    })
}

pub(crate) fn compute_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    entry: &str,
    constants: &[(&str, f64)],
) -> wgpu::ComputePipeline {
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry),
        layout: Some(layout),
        module,
        entry_point: Some(entry),
        compilation_options: wgpu::PipelineCompilationOptions {
            constants,
            ..Default::default()
        },
        cache: None,
    })
}

/// The pipeline constant `name` (`COMPACT_RSM`, `COMPACT_GBUFFER`) that says whether what a
/// pipeline reads is in the compact layout.
pub(crate) fn compact_constant(name: &'static str, layout: GBufferLayout) -> (&'static str, f64) {
    (name, f64::from(u8::from(layout == GBufferLayout::Compact)))
}

pub(crate) fn whole(buffer: &wgpu::Buffer) -> wgpu::BindingResource<'_> {
    buffer.as_entire_binding()
}

pub(crate) fn tex(view: &wgpu::TextureView) -> wgpu::BindingResource<'_> {
    wgpu::BindingResource::TextureView(view)
}

pub(crate) fn dispatch_2d(pass: &mut wgpu::ComputePass, width: u32, height: u32) {
    pass.dispatch_workgroups(width.div_ceil(8), height.div_ceil(8), 1);
}

/// Dispatches a sum over `items` takes, `per_slice` items each.
pub(crate) fn slices(items: u64, per_slice: u32) -> u32 {
    items
        .div_ceil(u64::from(per_slice))
        .clamp(1, u64::from(MAX_SLICES)) as u32
}

/// A compute pass, timed into `slot` of the timer when there is one.
pub(crate) fn compute_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    label: &str,
    timestamps: Option<wgpu::ComputePassTimestampWrites<'e>>,
) -> wgpu::ComputePass<'e> {
    encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(label),
        timestamp_writes: timestamps,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slices_cover_the_longest_sums_that_settings_allow() {
        // the largest RSM's VPLs (brute force, a cut of single VPLs), its finest level in level
        // slices (per-level passes), the most RSM samples: never clamped by the slot count
        let vpls = 1024u64 * 1024;
        for (items, per_slice) in [(vpls, SLICE), (vpls, LEVEL_SLICE), (65536, SLICE)] {
            let n = slices(items, per_slice);
            assert!(
                u64::from(n) * u64::from(per_slice) >= items,
                "{items} in {n} x {per_slice}"
            );
            assert!(n <= MAX_SLICES);
        }
        assert_eq!(slices(0, SLICE), 1, "an empty sum still writes its zeros");
        assert_eq!(slices(u64::from(SLICE) + 1, SLICE), 2);
    }

    #[test]
    fn the_prelude_holds_the_rust_constants() {
        let prelude = prelude();
        for line in [
            format!("const SLICE: u32 = {SLICE}u;"),
            format!("const LEVEL_SLICE: u32 = {LEVEL_SLICE}u;"),
            format!("const MAX_LEVELS: u32 = {MAX_LEVELS}u;"),
            format!("const TILE_FRONTIER: u32 = {TILE_FRONTIER}u;"),
            format!("const TILE_ENTRY_INDEX_BITS: u32 = {TILE_ENTRY_INDEX_BITS}u;"),
            format!("const TILE_SHADOW_HEADER: u32 = {TILE_SHADOW_HEADER}u;"),
            format!("const MOST_WALKED_TILES: u32 = {MOST_WALKED_TILES}u;"),
            format!("const TILE: u32 = {TILE}u;"),
            format!("const NEAR_FIELD_SIZE: f32 = {NEAR_FIELD_SIZE:?};"),
            format!("const EMPTY_BOX: f32 = {EMPTY_BOX:?};"),
            format!("const CONE_SLACK: f32 = {CONE_SLACK:?};"),
            format!("const SPLIT_BINS: u32 = {SPLIT_BINS}u;"),
            format!("const MIXED_TARGET_ANGLE: f32 = {MIXED_TARGET_ANGLE:?};"),
            format!("const PARALLEL_TARGET_COS: f32 = {PARALLEL_TARGET_COS:?};"),
            format!("const DEBLOCK_LIMIT: f32 = {DEBLOCK_LIMIT:?};"),
            format!("const DEBLOCK_PLANE: f32 = {DEBLOCK_PLANE:?};"),
            format!("const DEBLOCK_ALBEDO: f32 = {DEBLOCK_ALBEDO:?};"),
        ] {
            assert!(prelude.contains(&line), "{line}");
        }
    }
}
