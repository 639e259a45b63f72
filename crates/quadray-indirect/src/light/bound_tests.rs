//! The bound of a node's contribution to a box of receivers (`bound.wgsl`, per-tile cuts) held
//! against the CPU reference's exact irradiance. Here, above every pass, since it reads the
//! reference.

use crate::contract::{
    bind_group, compute_pipeline, layout, pipeline_layout, shader_module, storage_buffer,
    storage_entry, whole,
};
use crate::frame::{Receiver, Vpl};
use crate::reference::{brute_force, luminance};
use crate::wgsl;
use glam::Vec3;
use quadray_core::random::SplitMix;
use wgpu::util::DeviceExt;

/// `node_bound`'s inputs (one case), and the entry point that evaluates it per case.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct BoundCase {
    flux: [f32; 4],
    /// the node's box (w of lo: its cone's cosine) and cone axis
    node_lo: [f32; 4],
    node_hi: [f32; 4],
    node_axis: [f32; 4],
    /// the receivers' box (w of lo: their cone's cosine), cone axis (w: r_min)
    lo: [f32; 4],
    hi: [f32; 4],
    axis: [f32; 4],
}

const ENTRY: &str = "
struct BoundCase { flux: vec4<f32>, node_lo: vec4<f32>, node_hi: vec4<f32>, node_axis: vec4<f32>,
lo: vec4<f32>, hi: vec4<f32>, axis: vec4<f32> }
@group(0) @binding(0) var<storage, read> cases: array<BoundCase>;
@group(0) @binding(1) var<storage, read_write> bound: array<f32>;
@compute @workgroup_size(64)
fn bound_cases(@builtin(global_invocation_id) id: vec3<u32>) {
if (id.x < arrayLength(&cases)) {
    let c = cases[id.x];
    bound[id.x] = node_bound(c.flux.rgb, NodeBounds(c.node_lo, c.node_hi), c.node_axis.xyz,
        c.lo.xyz, c.hi.xyz, c.axis.xyz, c.lo.w, c.axis.w);
}
}
";

fn bounds_on_the_gpu(cases: &[BoundCase]) -> Vec<f32> {
    let gpu = quadray_gpu::Gpu::new().expect("an adapter (run scripts/setup.sh for lavapipe)");
    let d = &gpu.device;
    let group_layout = layout(
        d,
        "bound cases",
        &[
            storage_entry::<BoundCase>(0, true),
            storage_entry::<f32>(1, false),
        ],
    );
    let module = shader_module(
        d,
        "bound cases",
        &[wgsl::NODE, wgsl::KERNEL, wgsl::BOUND, ENTRY],
    );
    let pipeline = compute_pipeline(
        d,
        &pipeline_layout(d, &[&group_layout]),
        &module,
        "bound_cases",
        &[],
    );
    let input = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("bound cases"),
        contents: bytemuck::cast_slice(cases),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let output = storage_buffer(d, "bounds", cases.len() as u64 * 4);
    let group = bind_group(
        d,
        "bound cases",
        &group_layout,
        vec![whole(&input), whole(&output)],
    );
    let mut encoder = d.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups((cases.len() as u32).div_ceil(64), 1, 1);
    }
    gpu.queue.submit([encoder.finish()]);
    let bytes = quadray_gpu::read_buffer(&gpu, &output).unwrap();
    bytemuck::pod_collect_to_vec(&bytes)
}

struct Random(SplitMix);

impl Random {
    fn unit(&mut self) -> f32 {
        self.0.next_f32()
    }
    fn vec(&mut self, lo: f32, hi: f32) -> Vec3 {
        Vec3::new(self.unit(), self.unit(), self.unit()) * (hi - lo) + lo
    }
    fn direction(&mut self) -> Vec3 {
        loop {
            let v = self.vec(-1.0, 1.0);
            if v.length_squared() > 1e-3 && v.length_squared() <= 1.0 {
                return v.normalize();
            }
        }
    }
    /// A unit vector at `angle` or less from `axis`, often exactly at it (the cone's rim).
    fn within(&mut self, axis: Vec3, angle: f32) -> Vec3 {
        let across = axis
            .cross(self.direction())
            .normalize_or(axis.any_orthonormal_vector());
        let turn = if self.unit() < 0.3 {
            angle
        } else {
            angle * self.unit()
        };
        axis * turn.cos() + across * turn.sin()
    }
    /// A box, flat along one axis a third of the time (a wall), and a point in it.
    fn box_around(&mut self, centre: Vec3, size: f32) -> (Vec3, Vec3) {
        let mut half = self.vec(0.0, size);
        if self.unit() < 0.33 {
            half[(self.unit() * 3.0) as usize % 3] = 0.0;
        }
        (centre - half, centre + half)
    }
    fn inside(&mut self, (lo, hi): (Vec3, Vec3)) -> Vec3 {
        lo + (hi - lo) * self.vec(0.0, 1.0)
    }
}

#[test]
fn the_node_bound_is_at_least_the_exact_irradiance_at_any_receiver_of_the_box() {
    let mut rng = Random(SplitMix(7));
    let (cases, per_case) = (512, 24);
    let mut all = Vec::new();
    let mut exact = Vec::new();
    for case in 0..cases {
        // near boxes (overlapping, within r_min) and far ones, narrow and wide cones
        let spread = if case % 2 == 0 { 0.6 } else { 3.0 };
        let centres = [rng.vec(-spread, spread), rng.vec(-spread, spread)];
        let node_box = rng.box_around(centres[0], 0.4);
        let receiver_box = rng.box_around(centres[1], 0.4);
        let node_axis = rng.direction();
        let receiver_axis = rng.direction();
        let angles = [0.0, 0.3, 1.2, 2.0];
        let node_angle = angles[case % 4];
        let receiver_angle = angles[(case / 4) % 4];
        let r_min = [0.01, 0.2][(case / 16) % 2];
        let vpls: Vec<Vpl> = (0..per_case)
            .map(|_| Vpl {
                flux: rng.vec(0.0, 1.0).into(),
                position: rng.inside(node_box).into(),
                normal: rng.within(node_axis, node_angle).into(),
            })
            .collect();
        let receivers: Vec<Option<Receiver>> = (0..per_case)
            .map(|_| {
                Some(Receiver {
                    position: rng.inside(receiver_box).into(),
                    normal: rng.within(receiver_axis, receiver_angle).into(),
                    // radiance albedo / pi * E is then the irradiance E
                    albedo: [std::f32::consts::PI; 3],
                })
            })
            .collect();
        let irradiance = brute_force(&vpls, &receivers, r_min);
        exact.push(
            irradiance
                .into_iter()
                .map(|c| luminance(Vec3::from(c)))
                .fold(0.0, f32::max),
        );
        let flux = vpls.iter().fold(Vec3::ZERO, |s, v| s + Vec3::from(v.flux));
        all.push(BoundCase {
            flux: flux.extend(0.0).into(),
            node_lo: node_box.0.extend(node_angle.cos()).into(),
            node_hi: node_box.1.extend(0.0).into(),
            node_axis: node_axis.extend(0.0).into(),
            lo: receiver_box.0.extend(receiver_angle.cos()).into(),
            hi: receiver_box.1.extend(0.0).into(),
            axis: receiver_axis.extend(r_min).into(),
        });
    }
    let bounds = bounds_on_the_gpu(&all);
    let mut tightness = Vec::new();
    for (i, (&bound, &exact)) in bounds.iter().zip(&exact).enumerate() {
        assert!(
            bound >= exact * (1.0 - 1e-4),
            "case {i}: bound {bound} < exact {exact}"
        );
        if exact > 0.0 {
            tightness.push(exact / bound);
        }
    }
    // the bound follows the light: it is not a constant over the cases
    tightness.sort_by(f32::total_cmp);
    let median = tightness[tightness.len() / 2];
    let zero = bounds.iter().filter(|&&b| b == 0.0).count();
    println!(
        "{} of {cases} cases lit; exact / bound median {median:.3}; {zero} bounds 0",
        tightness.len()
    );
    assert!(
        median > 0.03,
        "bound too loose: median exact / bound {median}"
    );
    assert!(zero > 0, "no case told back-facing nodes apart");
}
