//! Extract, prepare and record, the lights' RSMs drawn from Bevy's meshes
//! ([`RsmSource::Meshes`]): a mesh pipeline specialised per mesh layout ([`RsmMeshPipeline`]:
//! Bevy's vertex layouts and mesh bind group layouts, Bevy's skinning in the vertex stage,
//! quadray's RSM fragment stage), one draw per mesh Bevy extracted from its mesh allocator's
//! slabs, the entity's `StandardMaterial`'s base colour and texture as the albedo.

use super::light::LightState;
use super::triangles::SceneWork;
use crate::gi::cpu_time::CpuTimes;
use crate::gi::scene::RsmSource;
use bevy::asset::{AssetEvent, uuid_handle};
use bevy::math::{Affine2, Affine3, Affine3Ext};
use bevy::mesh::{MeshVertexBufferLayoutRef, PrimitiveTopology, UvChannel};
use bevy::pbr::{
    MeshInputUniform, MeshLayouts, MeshPipeline, MeshPipelineKey, MeshUniform,
    RenderMaterialInstances, RenderMeshInstances, SkinUniforms, StandardMaterial,
    setup_morph_and_skinning_defs,
};
use bevy::platform::collections::HashMap;
use bevy::prelude::*;
use bevy::render::Extract;
use bevy::render::batching::gpu_preprocessing::BatchedInstanceBuffers;
use bevy::render::mesh::allocator::MeshAllocator;
use bevy::render::mesh::{RenderMesh, RenderMeshBufferInfo};
use bevy::render::render_asset::{ExtractedAssets, RenderAssets};
use bevy::render::render_resource::binding_types::{sampler, texture_2d, uniform_buffer_sized};
use bevy::render::render_resource::{
    BindGroup, BindGroupEntries, BindGroupLayoutDescriptor, BindGroupLayoutEntries,
    BufferInitDescriptor, BufferUsages, CachedRenderPipelineId, CompareFunction, DepthStencilState,
    FragmentState, IndexFormat, PipelineCache, PrimitiveState, RenderPipelineDescriptor,
    SamplerBindingType, ShaderStages, SpecializedMeshPipeline, SpecializedMeshPipelineError,
    SpecializedMeshPipelines, StorageBuffer, TextureSampleType, VertexState,
};
use bevy::render::render_resource::{BindGroupId, BufferId, SamplerId, TextureId};
use bevy::render::renderer::{RenderDevice, RenderQueue};
use bevy::render::sync_world::MainEntity;
use bevy::render::texture::{FallbackImage, GpuImage};
use bevy::shader::Shader;
use quadray_indirect::{GBufferLayout, RsmPass};
use std::ops::Range;

/// The RSM's mesh shader ([`rsm_mesh_source`]).
pub(super) const RSM_MESH_SHADER: Handle<Shader> =
    uuid_handle!("3e7c9a51-2b84-4f6d-9c0e-71d5a8b3f246");

/// The RSM's mesh shader: Bevy's mesh bindings and skinning, quadray's RSM fragment stage, then
/// the vertex stage and the albedo (`rsm_meshes.wgsl`).
pub(super) fn rsm_mesh_source() -> String {
    [
        "#import bevy_pbr::mesh_bindings::mesh\n",
        "#import bevy_pbr::skinning\n",
        "#import bevy_render::maths::{affine3_to_square, mat2x4_f32_to_mat3x3_unpack}\n",
        RsmPass::fragment_source().as_str(),
        include_str!("rsm_meshes.wgsl"),
    ]
    .concat()
}

/// A `StandardMaterial` as the RSM reads it.
#[derive(Clone, Copy)]
struct RsmMaterial {
    /// The base colour times 1 - metallic (linear).
    albedo: Vec3,
    texture: Option<AssetId<Image>>,
    uv_transform: Affine2,
    /// It reads its texture at the second uv channel.
    uv1: bool,
}

impl RsmMaterial {
    fn of(material: &StandardMaterial) -> Self {
        Self {
            albedo: crate::gi::scene::base_albedo(material),
            texture: material.base_color_texture.as_ref().map(Handle::id),
            uv_transform: material.uv_transform,
            uv1: material.base_color_channel == UvChannel::Uv1,
        }
    }

    /// A mesh without a `StandardMaterial`, as the CPU's triangles take it.
    const GREY: Self = Self {
        albedo: Vec3::splat(0.5),
        texture: None,
        uv_transform: Affine2::IDENTITY,
        uv1: false,
    };

    /// The uniform `rsm_meshes.wgsl` reads.
    fn uniform(&self) -> [Vec4; 3] {
        let m = self.uv_transform.matrix2;
        let t = self.uv_transform.translation;
        [
            self.albedo.extend(1.0),
            Vec4::new(m.x_axis.x, m.x_axis.y, m.y_axis.x, m.y_axis.y),
            Vec4::new(t.x, t.y, 0.0, 0.0),
        ]
    }
}

/// The main world's `StandardMaterial`s as the RSM reads them, kept by their asset events, and
/// each one's bind group once made (made anew when it changes, or while its texture loads).
#[derive(Resource, Default)]
pub(super) struct RsmMaterials {
    materials: HashMap<AssetId<StandardMaterial>, RsmMaterial>,
    /// Each material's group and what it bound: its texture and sampler, or `None` for the
    /// fallback's white while the texture is not on the GPU.
    groups: HashMap<AssetId<StandardMaterial>, (BindGroup, Option<BoundImage>)>,
    grey: Option<BindGroup>,
    /// Counts the frames in which a material changed.
    generation: u64,
}

pub(super) fn extract_materials(
    mut events: Extract<MessageReader<AssetEvent<StandardMaterial>>>,
    assets: Extract<Res<Assets<StandardMaterial>>>,
    mut materials: ResMut<RsmMaterials>,
    times: Res<CpuTimes>,
) {
    let _span = times.render();
    for event in events.read() {
        if !matches!(event, AssetEvent::Unused { .. }) {
            materials.generation += 1;
        }
        match *event {
            AssetEvent::Added { id }
            | AssetEvent::Modified { id }
            | AssetEvent::LoadedWithDependencies { id } => {
                materials.groups.remove(&id);
                match assets.get(id) {
                    Some(m) => materials.materials.insert(id, RsmMaterial::of(m)),
                    None => materials.materials.remove(&id),
                };
            }
            AssetEvent::Removed { id } => {
                materials.groups.remove(&id);
                materials.materials.remove(&id);
            }
            AssetEvent::Unused { .. } => {}
        }
    }
}

/// The RSM's mesh pipelines: quadray's RSM group (0), the material (1) and Bevy's mesh bind
/// group (2) as Bevy's mesh pipeline lays it out for the mesh.
#[derive(Resource)]
pub(super) struct RsmMeshPipeline {
    mesh_layouts: MeshLayouts,
    /// Bevy's mesh uniforms and joints are in storage buffers, as the draws bind them (not on
    /// platforms without storage buffers, where Bevy batches them in uniform buffers).
    storage_buffers: bool,
    pub(super) uniforms_layout: BindGroupLayoutDescriptor,
    pub(super) material_layout: BindGroupLayoutDescriptor,
}

pub(super) fn init_rsm_mesh_pipeline(mut commands: Commands, mesh_pipeline: Res<MeshPipeline>) {
    let uniforms_layout = BindGroupLayoutDescriptor::new(
        "quadray gi rsm uniforms",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::VERTEX_FRAGMENT,
            (
                uniform_buffer_sized(false, None),
                uniform_buffer_sized(false, None),
            ),
        ),
    );
    let material_layout = BindGroupLayoutDescriptor::new(
        "quadray gi rsm material",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::VERTEX_FRAGMENT,
            (
                uniform_buffer_sized(false, None),
                texture_2d(TextureSampleType::Float { filterable: true }),
                sampler(SamplerBindingType::Filtering),
            ),
        ),
    );
    commands.insert_resource(RsmMeshPipeline {
        mesh_layouts: mesh_pipeline.mesh_layouts.clone(),
        storage_buffers: mesh_pipeline.per_object_buffer_batch_size.is_none()
            && !mesh_pipeline.skins_use_uniform_buffers,
        uniforms_layout,
        material_layout,
    });
}

/// What an RSM mesh pipeline is specialised by besides the mesh's vertex layout.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) struct RsmMeshKey {
    /// The mesh's topology (Bevy's key bits).
    mesh: MeshPipelineKey,
    compact: bool,
    /// The material reads its texture at the second uv channel.
    uv1: bool,
}

impl SpecializedMeshPipeline for RsmMeshPipeline {
    type Key = RsmMeshKey;

    fn specialize(
        &self,
        key: Self::Key,
        layout: &MeshVertexBufferLayoutRef,
    ) -> Result<RenderPipelineDescriptor, SpecializedMeshPipelineError> {
        let mut shader_defs = Vec::new();
        let mut attributes = vec![
            Mesh::ATTRIBUTE_POSITION.at_shader_location(0),
            Mesh::ATTRIBUTE_NORMAL.at_shader_location(1),
        ];
        let uv = if key.uv1 {
            Mesh::ATTRIBUTE_UV_1
        } else {
            Mesh::ATTRIBUTE_UV_0
        };
        if layout.0.contains(uv) {
            shader_defs.push("VERTEX_UVS".into());
            attributes.push(uv.at_shader_location(2));
        }
        // skinned or not, as Bevy's mesh pipeline lays the mesh out (no morph targets: the key
        // does not ask for them)
        let mesh_layout = setup_morph_and_skinning_defs(
            &self.mesh_layouts,
            layout,
            3,
            &key.mesh,
            &mut shader_defs,
            &mut attributes,
            false,
        );
        let buffer = layout.0.get_layout(&attributes)?;
        let gbuffer = if key.compact {
            GBufferLayout::Compact
        } else {
            GBufferLayout::Wide
        };
        let targets = RsmPass::target_formats(gbuffer)
            .into_iter()
            .map(|format| Some(format.into()))
            .collect();
        Ok(RenderPipelineDescriptor {
            label: Some("quadray gi rsm mesh".into()),
            layout: vec![
                self.uniforms_layout.clone(),
                self.material_layout.clone(),
                mesh_layout,
            ],
            vertex: VertexState {
                shader: RSM_MESH_SHADER,
                shader_defs: shader_defs.clone(),
                entry_point: Some("mesh_vertex".into()),
                buffers: vec![buffer],
            },
            fragment: Some(FragmentState {
                shader: RSM_MESH_SHADER,
                shader_defs,
                entry_point: Some(RsmPass::fragment_entry(gbuffer).into()),
                targets,
            }),
            // both faces, as quadray's RSM pass draws them
            primitive: PrimitiveState {
                topology: key.mesh.primitive_topology(),
                strip_index_format: key.mesh.strip_index_format(),
                ..default()
            },
            depth_stencil: Some(DepthStencilState {
                format: RsmPass::DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(CompareFunction::Greater),
                stencil: default(),
                bias: default(),
            }),
            ..default()
        })
    }
}

/// One mesh entity's draw into every RSM.
struct MeshDraw {
    geometry: MeshGeometry,
    material: BindGroup,
}

/// A mesh's pipeline, slabs and skinning.
#[derive(Clone)]
struct MeshGeometry {
    pipeline: CachedRenderPipelineId,
    skinned: bool,
    vertices: (bevy::render::render_resource::Buffer, Range<u32>),
    /// Indexed: the index buffer, its range and format.
    indices: Option<(
        bevy::render::render_resource::Buffer,
        Range<u32>,
        IndexFormat,
    )>,
}

/// What an entity's mesh uniform is made from: its transform (Bevy's transposed affine), its
/// flags, its first vertex in its slab and its skin (`u32::MAX`: none).
#[derive(Clone, Copy, PartialEq)]
struct UniformInput {
    world_from_local: [Vec4; 3],
    flags: u32,
    first_vertex: u32,
    skin: u32,
}

impl UniformInput {
    /// The mesh uniform as Bevy's mesh shaders read it.
    fn uniform(&self) -> MeshUniform {
        let world_from_local = Affine3::from_transpose(self.world_from_local);
        let (local_from_world_transpose_a, local_from_world_transpose_b) =
            world_from_local.inverse_transpose_3x3();
        MeshUniform {
            world_from_local: self.world_from_local,
            previous_world_from_local: self.world_from_local,
            lightmap_uv_rect: UVec2::ZERO,
            local_from_world_transpose_a,
            local_from_world_transpose_b,
            flags: self.flags,
            first_vertex_index: self.first_vertex,
            current_skin_index: self.skin,
            material_and_lightmap_bind_group_slot: 0,
            tag: 0,
            morph_descriptor_index: u32::MAX,
        }
    }
}

/// An entity's draw as last prepared, kept while its mesh and material are the same and no mesh
/// was uploaded or freed (which may move a mesh in Bevy's slabs).
struct CachedDraw {
    mesh: AssetId<Mesh>,
    material: Option<AssetId<StandardMaterial>>,
    /// (its material's group is looked up each frame: it is made again when its texture loads
    /// or is replaced)
    geometry: MeshGeometry,
    input: UniformInput,
    uniform: MeshUniform,
    /// The last frame ([`MeshDraws::frame`]) that drew it.
    frame: u64,
}

/// The meshes' draws into the RSMs ([`record_mesh_rsm`]): their mesh uniforms (the draw's
/// instance index is its place), Bevy's mesh bind groups over them, each light view's group 0;
/// and each entity's draw kept across frames, so that a frame in which nothing moved makes no
/// draw and sets no RSM to be drawn again.
#[derive(Resource, Default)]
pub(super) struct MeshDraws {
    draws: Vec<MeshDraw>,
    uniforms: StorageBuffer<Vec<MeshUniform>>,
    model_only: Option<BindGroup>,
    skinned: Option<BindGroup>,
    views: Vec<BindGroup>,
    /// Each entity's draw, and what it was prepared under: the RSM layout, the materials'
    /// generation, the count of meshes on the GPU.
    cache: HashMap<MainEntity, CachedDraw>,
    prepared_for: (bool, u64, usize),
    /// Counts the frames prepared (an entity's kept draw not drawn this frame is dropped).
    frame: u64,
    /// Last frame's draws: entity, pipeline, material group (the RSMs are drawn again when
    /// they differ).
    last: Vec<(MainEntity, CachedRenderPipelineId, BindGroupId)>,
    /// Bevy's joint matrices when the skinned meshes were last drawn.
    joints: Vec<Mat4>,
    /// The light views' uniform buffers that [`Self::views`] bind.
    view_uniforms: Vec<[wgpu::Buffer; 2]>,
    /// The mesh uniforms' and Bevy's joints' buffers that the mesh groups bind.
    mesh_groups_bound: Option<(Option<BufferId>, BufferId)>,
}

/// The Bevy resources the draws are made from.
#[derive(bevy::ecs::system::SystemParam)]
pub(super) struct MeshSources<'w> {
    instances: Res<'w, RenderMeshInstances>,
    material_instances: Res<'w, RenderMaterialInstances>,
    meshes: Res<'w, RenderAssets<RenderMesh>>,
    uploaded: Res<'w, ExtractedAssets<RenderMesh>>,
    allocator: Res<'w, MeshAllocator>,
    images: Res<'w, RenderAssets<GpuImage>>,
    fallback: Res<'w, FallbackImage>,
    skins: Res<'w, SkinUniforms>,
    batched: Option<Res<'w, BatchedInstanceBuffers<MeshUniform, MeshInputUniform>>>,
}

/// Specialises the pipelines and prepares this frame's draws, when the lights' RSMs are drawn
/// from Bevy's meshes; sets the RSMs to be drawn again when the draws changed (an entity moved,
/// came or went, its mesh or material changed, a skinned mesh's joints moved, or a pipeline is
/// still compiling).
#[allow(clippy::too_many_arguments)]
pub(super) fn prepare_mesh_rsm(
    mut light: ResMut<LightState>,
    sources: MeshSources,
    mut materials: ResMut<RsmMaterials>,
    pipeline: Res<RsmMeshPipeline>,
    mut pipelines: ResMut<SpecializedMeshPipelines<RsmMeshPipeline>>,
    pipeline_cache: Res<PipelineCache>,
    (device, queue): (Res<RenderDevice>, Res<RenderQueue>),
    (mut draws, mut warned): (ResMut<MeshDraws>, Local<bool>),
    times: Res<CpuTimes>,
) {
    let _span = times.render();
    let draws = &mut *draws;
    let Some(l) = light.0.as_mut().filter(|l| l.source == RsmSource::Meshes) else {
        draws.draws.clear();
        draws.cache.clear();
        draws.last.clear();
        return;
    };
    if !pipeline.storage_buffers {
        if !std::mem::replace(&mut *warned, true) {
            warn!(
                "quadray indirect light: RsmSource::Meshes needs storage buffers, which this \
                 platform lacks: the RSMs stay empty; use RsmSource::Triangles"
            );
        }
        return;
    }
    let compact = l.rsm_layout == GBufferLayout::Compact;
    // (a mesh freed changes the count)
    let prepared_for = (compact, materials.generation, sources.meshes.iter().count());
    // a mesh uploaded may grow a slab, so move the meshes in it
    let uploaded = !sources.uploaded.added.is_empty() || !sources.uploaded.modified.is_empty();
    if uploaded || draws.prepared_for != prepared_for {
        draws.cache.clear();
        draws.prepared_for = prepared_for;
    }
    let material_layout = pipeline_cache.get_bind_group_layout(&pipeline.material_layout);
    draws.frame += 1;
    let frame = draws.frame;
    let (mut uniforms_changed, mut redraw, mut skinned) = (false, false, false);
    draws.draws.clear();
    let mut uniforms = Vec::new();
    let mut now = Vec::new();
    for (entity, mesh_id, input) in uniform_inputs(&sources) {
        let material_id = sources
            .material_instances
            .instances
            .get(&entity)
            .and_then(|m| m.asset_id.try_typed::<StandardMaterial>().ok());
        let material = match material_id {
            Some(id) => match materials.materials.get(&id) {
                Some(m) => Some((id, *m)),
                // (not extracted yet)
                None => continue,
            },
            None => None,
        };
        let cached = draws
            .cache
            .get_mut(&entity)
            .filter(|c| c.mesh == mesh_id && c.material == material_id);
        let cached = match cached {
            Some(c) => {
                if c.input != input {
                    c.input = input;
                    c.uniform = input.uniform();
                    uniforms_changed = true;
                }
                c
            }
            None => {
                let Some(made) = prepare_draw(
                    &sources,
                    (mesh_id, material.map(|(_, m)| m.uv1)),
                    compact,
                    input,
                    (&pipeline, &mut pipelines, &pipeline_cache),
                ) else {
                    continue;
                };
                uniforms_changed = true;
                draws
                    .cache
                    .entry(entity)
                    .insert(CachedDraw {
                        material: material_id,
                        ..made
                    })
                    .into_mut()
            }
        };
        let geometry = &cached.geometry;
        if geometry.skinned && input.skin == u32::MAX {
            continue;
        }
        cached.frame = frame;
        let group = material_group(
            &mut materials,
            material,
            &sources,
            &device,
            &material_layout,
        );
        skinned |= geometry.skinned;
        redraw |= pipeline_cache
            .get_render_pipeline(geometry.pipeline)
            .is_none();
        now.push((entity, geometry.pipeline, group.id()));
        draws.draws.push(MeshDraw {
            geometry: geometry.clone(),
            material: group,
        });
        uniforms.push(cached.uniform.clone());
    }
    draws.cache.retain(|_, c| c.frame == frame);
    let listed = uniforms_changed || now != draws.last;
    // skinned meshes move with their joints, which Bevy poses on the GPU from its joint matrices
    let joints = &sources.skins.current_staging_buffer;
    if skinned && *joints != draws.joints {
        draws.joints.clone_from(joints);
        redraw = true;
    }
    redraw |= listed;
    draws.last = now;
    l.stale |= redraw;
    if !l.stale || draws.draws.is_empty() {
        return;
    }
    // (the groups and uniforms written again only where what they hold changed)
    let view_uniforms: Vec<[wgpu::Buffer; 2]> = l
        .views
        .iter()
        .map(|v| v.rsm.uniforms().map(Clone::clone))
        .collect();
    if view_uniforms != draws.view_uniforms {
        let uniforms_layout = pipeline_cache.get_bind_group_layout(&pipeline.uniforms_layout);
        draws.views = view_uniforms
            .iter()
            .map(|[raster, light]| {
                device.create_bind_group(
                    "quadray gi rsm uniforms",
                    &uniforms_layout,
                    &BindGroupEntries::sequential((
                        raster.as_entire_binding(),
                        light.as_entire_binding(),
                    )),
                )
            })
            .collect();
        draws.view_uniforms = view_uniforms;
    }
    if listed || draws.uniforms.buffer().is_none() {
        draws.uniforms.set(uniforms);
        draws.uniforms.write_buffer(&device, &queue);
    }
    let Some(model) = draws.uniforms.binding() else {
        return;
    };
    let bound = (
        draws.uniforms.buffer().map(|b| b.id()),
        sources.skins.current_buffer.id(),
    );
    if draws.mesh_groups_bound != Some(bound) {
        let layouts = &pipeline.mesh_layouts;
        draws.model_only = Some(layouts.model_only(&device, &pipeline_cache, &model));
        draws.skinned = Some(layouts.skinned(
            &device,
            &pipeline_cache,
            &model,
            &sources.skins.current_buffer,
        ));
        draws.mesh_groups_bound = Some(bound);
    }
}

/// Entity `mesh`'s draw: its pipeline (specialised for its layout and whether its material reads
/// the second uv channel), its slabs; `None` for a mesh not drawn (not uploaded yet, not
/// triangles with normals, no pipeline).
fn prepare_draw(
    sources: &MeshSources,
    (mesh_id, uv1): (AssetId<Mesh>, Option<bool>),
    compact: bool,
    input: UniformInput,
    (pipeline, pipelines, pipeline_cache): (
        &RsmMeshPipeline,
        &mut SpecializedMeshPipelines<RsmMeshPipeline>,
        &PipelineCache,
    ),
) -> Option<CachedDraw> {
    let mesh = sources.meshes.get(mesh_id)?;
    let vertices = sources.allocator.mesh_vertex_slice(&mesh_id)?;
    // triangles with normals, as the triangles' RSM takes them
    let triangles = matches!(
        mesh.primitive_topology(),
        PrimitiveTopology::TriangleList | PrimitiveTopology::TriangleStrip
    );
    if !triangles || !mesh.layout.0.contains(Mesh::ATTRIBUTE_NORMAL) {
        return None;
    }
    // (laid out as Bevy's mesh pipeline lays the mesh out: skinned where it has joints)
    let skinned = mesh.layout.0.contains(Mesh::ATTRIBUTE_JOINT_INDEX)
        && mesh.layout.0.contains(Mesh::ATTRIBUTE_JOINT_WEIGHT);
    let key = RsmMeshKey {
        mesh: MeshPipelineKey::from_primitive_topology_and_strip_index(
            mesh.primitive_topology(),
            mesh.index_format(),
        ),
        compact,
        uv1: uv1.unwrap_or(false),
    };
    let id = pipelines
        .specialize(pipeline_cache, pipeline, key, &mesh.layout)
        .inspect_err(|e| error!("quadray indirect light: no RSM pipeline for a mesh: {e}"))
        .ok()?;
    let indices = match &mesh.buffer_info {
        RenderMeshBufferInfo::Indexed {
            count,
            index_format,
        } => {
            let slice = sources.allocator.mesh_index_slice(&mesh_id)?;
            let start = slice.range.start;
            Some((slice.buffer.clone(), start..start + count, *index_format))
        }
        RenderMeshBufferInfo::NonIndexed => None,
    };
    Some(CachedDraw {
        mesh: mesh_id,
        material: None,
        geometry: MeshGeometry {
            pipeline: id,
            skinned,
            vertices: (vertices.buffer.clone(), vertices.range.clone()),
            indices,
        },
        input,
        uniform: input.uniform(),
        frame: 0,
    })
}

/// Every mesh entity Bevy extracted, its mesh and what its mesh uniform is made from, by entity.
fn uniform_inputs(sources: &MeshSources) -> Vec<(MainEntity, AssetId<Mesh>, UniformInput)> {
    let mut out: Vec<(MainEntity, AssetId<Mesh>, UniformInput)> = match &*sources.instances {
        RenderMeshInstances::GpuBuilding(instances) => {
            let Some(batched) = sources.batched.as_ref() else {
                return Vec::new();
            };
            instances
                .iter()
                .filter_map(|(entity, instance)| {
                    let index = instance.gpu_specific.current_uniform_index();
                    let input = batched.current_input_buffer.get(index)?;
                    let uniform = UniformInput {
                        world_from_local: input.world_from_local,
                        flags: input.flags,
                        first_vertex: input.first_vertex_index,
                        skin: input.current_skin_index,
                    };
                    Some((*entity, instance.mesh_asset_id(), uniform))
                })
                .collect()
        }
        RenderMeshInstances::CpuBuilding(instances) => instances
            .iter()
            .map(|(entity, instance)| {
                let mesh = instance.mesh_asset_id();
                let first_vertex = sources
                    .allocator
                    .mesh_vertex_slice(&mesh)
                    .map_or(0, |s| s.range.start);
                let t = &instance.transforms;
                let uniform = UniformInput {
                    world_from_local: t.world_from_local.to_transpose(),
                    flags: t.flags,
                    first_vertex,
                    skin: sources.skins.skin_index(*entity).unwrap_or(u32::MAX),
                };
                (*entity, mesh, uniform)
            })
            .collect(),
    };
    // one order a frame, whatever the map's
    out.sort_by_key(|(entity, ..)| *entity);
    out
}

/// The texture and sampler a material's group binds. Bevy writes an edited image of the same
/// size into its texture, but makes a new texture for a new size and a new sampler for a new
/// sampler descriptor: a group that bound the old ones is made again.
type BoundImage = (TextureId, SamplerId);

/// A material's group: made once, again while its texture is not loaded and when its image's
/// texture or sampler is replaced.
fn material_group(
    materials: &mut RsmMaterials,
    material: Option<(AssetId<StandardMaterial>, RsmMaterial)>,
    sources: &MeshSources,
    device: &RenderDevice,
    layout: &bevy::render::render_resource::BindGroupLayout,
) -> BindGroup {
    let bound_image = |m: &RsmMaterial| {
        let image = m
            .texture
            .map_or(Some(&sources.fallback.d2), |id| sources.images.get(id));
        image.map(|image| (image.texture.id(), image.sampler.id()))
    };
    let make = |m: &RsmMaterial| {
        let image = m.texture.and_then(|id| sources.images.get(id));
        let image = image.unwrap_or(&sources.fallback.d2);
        let buffer = device.create_buffer_with_data(&BufferInitDescriptor {
            label: Some("quadray gi rsm material"),
            contents: bytemuck::cast_slice(&m.uniform()),
            usage: BufferUsages::UNIFORM,
        });
        let group = device.create_bind_group(
            "quadray gi rsm material",
            layout,
            &BindGroupEntries::sequential((
                buffer.as_entire_binding(),
                &image.texture_view,
                &image.sampler,
            )),
        );
        (group, bound_image(m))
    };
    let Some((id, material)) = material else {
        return materials
            .grey
            .get_or_insert_with(|| make(&RsmMaterial::GREY).0)
            .clone();
    };
    if let Some((group, Some(bound))) = materials.groups.get(&id)
        && bound_image(&material) == Some(*bound)
    {
        return group.clone();
    }
    let made = make(&material);
    materials.groups.insert(id, made.clone());
    made.0
}

/// Draws the meshes into light view `view`'s RSM (cleared, without a mesh), counting them into
/// `work`.
pub(super) fn record_mesh_rsm(
    encoder: &mut wgpu::CommandEncoder,
    (rsm, view): (&RsmPass, usize),
    draws: &MeshDraws,
    pipeline_cache: &PipelineCache,
    work: &mut SceneWork,
) {
    let mut pass = rsm.begin(encoder);
    let groups = (&draws.model_only, &draws.skinned, draws.views.get(view));
    let (Some(model_only), Some(skinned), Some(group)) = groups else {
        return;
    };
    pass.set_bind_group(0, Some(&**group), &[]);
    for (instance, draw) in (0u32..).zip(&draws.draws) {
        let Some(pipeline) = pipeline_cache.get_render_pipeline(draw.geometry.pipeline) else {
            continue;
        };
        pass.set_pipeline(pipeline);
        pass.set_bind_group(1, Some(&*draw.material), &[]);
        let mesh = if draw.geometry.skinned {
            skinned
        } else {
            model_only
        };
        pass.set_bind_group(2, Some(&**mesh), &[]);
        let (buffer, range) = &draw.geometry.vertices;
        pass.set_vertex_buffer(0, wgpu::Buffer::slice(buffer, ..));
        let instances = instance..instance + 1;
        match &draw.geometry.indices {
            Some((indices, range_of_indices, format)) => {
                pass.set_index_buffer(wgpu::Buffer::slice(indices, ..), *format);
                pass.draw_indexed(range_of_indices.clone(), range.start as i32, instances);
            }
            None => pass.draw(range.clone(), instances),
        }
        work.meshes_drawn += 1;
    }
}
