//! [`DirectLight`]: the light views' direct light on the caller's G-buffer, each view shadowed by
//! a shadow map of its own ([`super::shadow_map`]) sized for the picture, filtered by four
//! bilinear comparisons (PCF over 3x3 texels) with a normal offset. Runs over the gather's shared
//! groups, its own group 3 a view: the map's view, its depth and the comparison sampler.

use super::shadow_map::ShadowMaps;
use crate::contract::{
    ShadowUniform, bind_group, compute_pass, dispatch_2d, layout, tex, uniform_buffer,
    uniform_entry, whole,
};
use crate::gathers::gather::Gather;
use crate::light::view::LightView;
use crate::settings::Settings;
use glam::{Mat4, Vec3};
use quadray_gpu::{GpuTimer, Limit, LimitNeed};

/// The pass's own shader parts, after the gather's shared ones.
pub(crate) const WGSL: [&str; 1] = [include_str!("direct.wgsl")];

/// The direct light of a gather's light views, through their shadow maps: made for a
/// [`Gather`] (its settings' [`Settings::shadow_map_size`], its views), given the light views
/// and the camera with [`DirectLight::set_lights`], its maps recorded from the caller's
/// triangles ([`DirectLight::record_shadow_maps`], every frame the camera or a light moves: the
/// sun's map follows the camera), then [`DirectLight::record`] writes the gather's direct
/// radiance, which an [`crate::OutputPass`] adds to the bounce.
pub struct DirectLight {
    maps: ShadowMaps,
    pipeline: wgpu::ComputePipeline,
    /// Per light view: its map's view and the group binding it with the map.
    shadows: Vec<wgpu::Buffer>,
    groups: Vec<wgpu::BindGroup>,
}

impl DirectLight {
    /// What the shadow maps of `settings` need of the device's limits.
    pub fn limit_needs(settings: &Settings) -> Vec<LimitNeed> {
        let size = settings.shadow_map_size_or_default();
        vec![LimitNeed {
            limit: Limit::TextureDimension2d,
            needed: size.into(),
            needed_by: format!("--shadow-map-size {size}"),
        }]
    }

    /// The direct light of `gather`'s light views, a shadow map of its settings' size each.
    pub fn new(device: &wgpu::Device, gather: &Gather) -> Self {
        let res = gather.resources();
        let views = res.view_count();
        let maps = ShadowMaps::new(device, res.settings().shadow_map_size_or_default(), views);
        let compute = wgpu::ShaderStages::COMPUTE;
        let group_layout = layout(
            device,
            "direct shadow",
            &[
                uniform_entry::<ShadowUniform>(0, compute, false),
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: compute,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Depth,
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: compute,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison),
                    count: None,
                },
            ],
        );
        // bilinear comparisons: each tap weighs the four texels around it by distance
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("shadow map comparison"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            // reversed depth (`reversed_depth`): lit where the map's surface is at or behind
            compare: Some(wgpu::CompareFunction::GreaterEqual),
            ..Default::default()
        });
        let shadows: Vec<wgpu::Buffer> = (0..views)
            .map(|_| uniform_buffer::<ShadowUniform>(device, "direct shadow"))
            .collect();
        let groups = shadows
            .iter()
            .enumerate()
            .map(|(i, shadow)| {
                bind_group(
                    device,
                    "direct shadow",
                    &group_layout,
                    vec![
                        whole(shadow),
                        tex(maps.depth(i)),
                        wgpu::BindingResource::Sampler(&sampler),
                    ],
                )
            })
            .collect();
        let [pipeline] = res.pipelines(device, "direct", &WGSL, ["direct_light"], &[&group_layout]);
        Self {
            maps,
            pipeline,
            shadows,
            groups,
        }
    }

    /// Sets the light views (in the gather's order) and the camera the G-buffer is rendered from
    /// (`camera_view_proj`: world -> clip, depth 0..1) over a scene within `bounds` (min, max):
    /// the sun's map is fitted to the part of the bounds the camera sees.
    ///
    /// # Panics
    /// With another number of views than the gather has.
    pub fn set_lights(
        &self,
        queue: &wgpu::Queue,
        lights: &[LightView],
        camera_view_proj: Mat4,
        bounds: (Vec3, Vec3),
    ) {
        assert_eq!(lights.len(), self.shadows.len(), "one light view a map");
        let size = self.maps.size();
        for (i, (light, shadow)) in lights.iter().zip(&self.shadows).enumerate() {
            let view = light.shadow_view(camera_view_proj, bounds, size);
            self.maps.set_view(queue, i, &view);
            queue.write_buffer(shadow, 0, bytemuck::bytes_of(&view.shadow_uniform(size)));
        }
    }

    /// Records every light view's shadow map of `vertex_count` vertices of `vertices` (triangle
    /// lists of [`crate::scene::Vertex`]), timed into `timer`'s `slot`.
    pub fn record_shadow_maps(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        vertices: wgpu::BufferSlice,
        vertex_count: u32,
        timer: Option<(&GpuTimer, u32)>,
    ) {
        self.maps.record(encoder, vertices, vertex_count, timer);
    }

    /// Records the direct light of every light view into `gather`'s direct radiance (the gather
    /// this was made for, after its G-buffer and this frame's shadow maps), timed into `timer`'s
    /// `slot`.
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        gather: &Gather,
        timer: Option<(&GpuTimer, u32)>,
    ) {
        let res = gather.resources();
        let stamps = timer.and_then(|(t, slot)| t.compute_pass(slot));
        let mut pass = compute_pass(encoder, "direct", stamps);
        pass.set_pipeline(&self.pipeline);
        res.bind_dispatch(&mut pass, 0, 0);
        let (width, height) = res.size();
        for (view, group) in self.groups.iter().enumerate() {
            res.bind_groups(&mut pass, view);
            pass.set_bind_group(3, group, &[]);
            dispatch_2d(&mut pass, width, height);
        }
    }
}
