//! A large glTF scene made from a seed, for the GI plugin's benchmark at the scale of games:
//! hundreds of meshes (lumpy spheres of 500 to 5,000 triangles each, about a million in all)
//! scattered over a ground, a few meshes shared by several nodes, a sun, a camera over them
//! and one node named [`MOVER`] for `--move-node`. Written as one GLB (some 30 MB), so made in a
//! temporary folder, never kept in the repository.

use bevy::math::{Mat3, Quat, Vec3};
use quadray_core::random::SplitMix;
use serde_json::{Value, json};
use std::path::Path;

/// The name of the node a benchmark moves.
pub const MOVER: &str = "mover";

/// Triangles the scene has at least.
const TRIANGLES: usize = 1_000_000;

/// Meshes shared by [`COPIES`] nodes each.
const SHARED: usize = 4;
const COPIES: usize = 3;

/// What a written scene holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LargeScene {
    /// Triangles drawn (a shared mesh's once a node).
    pub triangles: usize,
    /// Meshes in the file.
    pub meshes: usize,
    /// Nodes with a mesh.
    pub nodes: usize,
    /// The triangles of the node named [`MOVER`].
    pub mover_triangles: usize,
}

/// One mesh: positions, normals and triangles.
struct Lump {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    indices: Vec<u32>,
}

/// A unit sphere of `slices` around and `slices / 2` from pole to pole, its radius waved.
fn lump(rng: &mut SplitMix, slices: u32) -> Lump {
    let stacks = slices / 2;
    let waves = [
        1.0 + (rng.next_f32() * 5.0).floor(),
        1.0 + (rng.next_f32() * 5.0).floor(),
    ];
    let phase = rng.next_f32() * std::f32::consts::TAU;
    let amplitude = 0.05 + 0.2 * rng.next_f32();
    let mut positions = Vec::new();
    for i in 0..=stacks {
        let theta = std::f32::consts::PI * i as f32 / stacks as f32;
        for j in 0..=slices {
            let phi = std::f32::consts::TAU * j as f32 / slices as f32;
            let (st, ct) = theta.sin_cos();
            // no wave at the poles: each is one point
            let r =
                1.0 + amplitude * st * (waves[0] * theta + phase).sin() * (waves[1] * phi).sin();
            let (sp, cp) = phi.sin_cos();
            positions.push(Vec3::new(st * cp, ct, st * sp) * r);
        }
    }
    let at = |i: u32, j: u32| i * (slices + 1) + j;
    let mut indices = Vec::new();
    for i in 0..stacks {
        for j in 0..slices {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            // one triangle at a pole, where the quad's top or bottom edge is a point
            if i + 1 != stacks {
                indices.extend([a, c, b]);
            }
            if i != 0 {
                indices.extend([a, d, c]);
            }
        }
    }
    // smooth normals: the faces' around each vertex (the seam's two copies apart)
    let mut normals = vec![Vec3::ZERO; positions.len()];
    for t in indices.chunks_exact(3) {
        let p = [0, 1, 2].map(|k| positions[t[k] as usize]);
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        for &k in t {
            normals[k as usize] += n;
        }
    }
    let normals = normals
        .into_iter()
        .map(|n| n.normalize_or(Vec3::Y))
        .collect();
    Lump {
        positions,
        normals,
        indices,
    }
}

/// The rotation that turns -z (a glTF camera's and light's forward) towards `direction`.
fn facing(direction: Vec3) -> Quat {
    let forward = direction.normalize();
    let right = forward.cross(Vec3::Y).normalize();
    let up = right.cross(forward);
    Quat::from_mat3(&Mat3::from_cols(right, up, -forward))
}

/// Writes the scene of `seed` to `path` (a `.glb`).
pub fn write_large_scene(path: &Path, seed: u64) -> std::io::Result<LargeScene> {
    let mut rng = SplitMix(seed);
    let mut bin: Vec<u8> = Vec::new();
    let (mut views, mut accessors, mut meshes, mut nodes) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let materials: Vec<Value> = (0..8)
        .map(|_| {
            let c = [
                0.2 + 0.7 * rng.next_f32(),
                0.2 + 0.7 * rng.next_f32(),
                0.2 + 0.7 * rng.next_f32(),
            ];
            json!({"pbrMetallicRoughness": {"baseColorFactor": [c[0], c[1], c[2], 1.0],
                   "metallicFactor": 0.0, "roughnessFactor": 0.8}})
        })
        .collect();
    // a view of `bytes` in the buffer and its accessor
    let mut accessor = |bytes: &[u8], count: usize, kind: &str, component: u32, extra: Value| {
        let view = views.len();
        views.push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len()}));
        bin.extend_from_slice(bytes);
        let mut a = json!({"bufferView": view, "componentType": component, "count": count,
                           "type": kind});
        if let (Value::Object(a), Value::Object(extra)) = (&mut a, extra) {
            a.extend(extra);
        }
        accessors.push(a);
        accessors.len() - 1
    };
    let mut add_mesh = |positions: &[Vec3], normals: &[Vec3], indices: &[u32], material: usize| {
        let (lo, hi) = positions
            .iter()
            .fold((Vec3::MAX, Vec3::MIN), |(lo, hi), p| {
                (lo.min(*p), hi.max(*p))
            });
        let floats = |v: &[Vec3]| -> Vec<u8> {
            v.iter()
                .flat_map(|p| p.to_array())
                .flat_map(f32::to_le_bytes)
                .collect()
        };
        let position = accessor(
            &floats(positions),
            positions.len(),
            "VEC3",
            5126,
            json!({"min": lo.to_array(), "max": hi.to_array()}),
        );
        let normal = accessor(&floats(normals), normals.len(), "VEC3", 5126, json!({}));
        let index_bytes: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let index = accessor(&index_bytes, indices.len(), "SCALAR", 5125, json!({}));
        meshes.push(
            json!({"primitives": [{"attributes": {"POSITION": position, "NORMAL": normal},
                                           "indices": index, "material": material}]}),
        );
        meshes.len() - 1
    };
    let ground = 80.0;
    let g = [
        [-ground, 0.0, -ground],
        [ground, 0.0, -ground],
        [ground, 0.0, ground],
        [-ground, 0.0, ground],
    ]
    .map(Vec3::from);
    let ground_mesh = add_mesh(&g, &[Vec3::Y; 4], &[0, 2, 1, 0, 3, 2], 0);
    nodes.push(json!({"name": "ground", "mesh": ground_mesh}));
    let mut scene = LargeScene {
        triangles: 2,
        meshes: 1,
        nodes: 1,
        mover_triangles: 0,
    };
    let mut lump_index = 0;
    while scene.triangles < TRIANGLES {
        let slices = 32 + 2 * (rng.next_f32() * 20.0) as u32;
        let l = lump(&mut rng, slices);
        let material = 1 + (rng.next_f32() * 7.0) as usize;
        let mesh = add_mesh(&l.positions, &l.normals, &l.indices, material);
        scene.meshes += 1;
        let copies = if lump_index < SHARED { COPIES } else { 1 };
        for copy in 0..copies {
            let scale = 0.5 + 1.5 * rng.next_f32();
            let at = Vec3::new(
                (rng.next_f32() * 2.0 - 1.0) * (ground - 5.0),
                scale,
                (rng.next_f32() * 2.0 - 1.0) * (ground - 5.0),
            );
            let name = if lump_index == SHARED {
                scene.mover_triangles = l.indices.len() / 3;
                MOVER.to_string()
            } else {
                format!("lump {lump_index}.{copy}")
            };
            nodes.push(
                json!({"name": name, "mesh": mesh, "translation": at.to_array(),
                              "scale": [scale, scale, scale]}),
            );
            scene.nodes += 1;
            scene.triangles += l.indices.len() / 3;
        }
        lump_index += 1;
    }
    let eye = Vec3::new(0.0, 45.0, 100.0);
    nodes.push(
        json!({"name": "camera", "camera": 0, "translation": eye.to_array(),
                      "rotation": facing(-eye).to_array()}),
    );
    nodes.push(json!({"name": "sun", "translation": [0.0, 50.0, 0.0],
                      "rotation": facing(Vec3::new(-0.4, -1.0, -0.3)).to_array(),
                      "extensions": {"KHR_lights_punctual": {"light": 0}}}));
    let root = json!({
        "asset": {"version": "2.0", "generator": "quadray-bevy-gi --large-scene"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "directional", "color": [1.0, 0.95, 0.9], "intensity": 2000.0}]}},
        "scene": 0,
        "scenes": [{"nodes": (0..nodes.len()).collect::<Vec<_>>()}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1,
                     "zfar": 1000.0, "aspectRatio": 1.0}}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": bin.len()}],
    });
    let mut text = serde_json::to_vec(&root).map_err(std::io::Error::other)?;
    text.resize(text.len().next_multiple_of(4), b' ');
    bin.resize(bin.len().next_multiple_of(4), 0);
    let mut glb = Vec::with_capacity(28 + text.len() + bin.len());
    glb.extend(0x4654_6C67u32.to_le_bytes());
    glb.extend(2u32.to_le_bytes());
    glb.extend(((28 + text.len() + bin.len()) as u32).to_le_bytes());
    glb.extend((text.len() as u32).to_le_bytes());
    glb.extend(0x4E4F_534Au32.to_le_bytes());
    glb.extend(text);
    glb.extend((bin.len() as u32).to_le_bytes());
    glb.extend(0x004E_4942u32.to_le_bytes());
    glb.extend(bin);
    std::fs::write(path, glb)?;
    Ok(scene)
}
