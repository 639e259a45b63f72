//! A large glTF scene made from a seed, for the GI plugin's benchmark at the scale of games:
//! hundreds of meshes (lumpy spheres of 500 to 5,000 triangles each, about a million in all)
//! scattered over a ground, a few meshes shared by several nodes, a sun, a camera over them
//! and one node named [`MOVER`] for `--move-node`. Most materials take their base colour from
//! one of a few small textures (PNGs in the GLB's buffer, on the lumps' spherical uvs), and one
//! tube is skinned to three joints, the middle one named [`BENDER`] for `--bend-node`: the
//! textures and the skinned mesh animating that games have. Written as one GLB (some 30 MB), so
//! made in a temporary folder, never kept in the repository.

use bevy::math::{Mat3, Quat, Vec3};
use quadray_core::random::SplitMix;
use serde_json::{Value, json};
use std::path::Path;

/// The name of the node a benchmark moves.
pub const MOVER: &str = "mover";

/// The name of the skinned tube's middle joint, which a benchmark bends.
pub const BENDER: &str = "bend";

/// The base colour textures' side in texels.
const TEXTURE_SIZE: u32 = 64;

/// Materials (of the lumps' 1 to 7) with a base colour texture: the first five.
const TEXTURED: usize = 5;

/// The skinned tube: vertices around, rings up (each ring's triangles two a step around), its
/// height and radius (m), and where its foot stands.
const TUBE_AROUND: u32 = 64;
const TUBE_RINGS: u32 = 25;
const TUBE_HEIGHT: f32 = 6.0;
const TUBE_RADIUS: f32 = 0.6;
const TUBE_FOOT: Vec3 = Vec3::new(10.0, 0.0, 20.0);

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
    /// The skinned tube's triangles.
    pub skinned_triangles: usize,
    /// Base colour textures (PNG images in the file).
    pub images: usize,
    /// Materials with a base colour texture.
    pub textured_materials: usize,
    /// Materials in the file.
    pub materials: usize,
}

/// One mesh: positions, normals, uvs and triangles.
struct Lump {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Vec<[f32; 2]>,
    indices: Vec<u32>,
}

/// A skinned mesh's joints and their weights a vertex.
struct Skinning {
    joints: Vec<[u16; 4]>,
    weights: Vec<[f32; 4]>,
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
    let (mut positions, mut uvs) = (Vec::new(), Vec::new());
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
            uvs.push([j as f32 / slices as f32, i as f32 / stacks as f32]);
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
        uvs,
        indices,
    }
}

/// The skinned tube standing at [`TUBE_FOOT`], open at both ends, and its skinning to three joints
/// [`TUBE_HEIGHT`] / 3 apart up its axis (at 0, 1/3 and 2/3 of it): a vertex between two joints
/// follows both in proportion, one above the top joint the top joint alone.
fn tube() -> (Lump, Skinning) {
    let (mut lump, mut skinning) = (
        Lump {
            positions: Vec::new(),
            normals: Vec::new(),
            uvs: Vec::new(),
            indices: Vec::new(),
        },
        Skinning {
            joints: Vec::new(),
            weights: Vec::new(),
        },
    );
    let step = TUBE_HEIGHT / 3.0;
    for ring in 0..TUBE_RINGS {
        let v = ring as f32 / (TUBE_RINGS - 1) as f32;
        let y = v * TUBE_HEIGHT;
        let along = (y / step).min(2.0);
        let below = (along.floor() as u16).min(1);
        let up = along - f32::from(below);
        for j in 0..=TUBE_AROUND {
            let u = j as f32 / TUBE_AROUND as f32;
            let (s, c) = (u * std::f32::consts::TAU).sin_cos();
            lump.positions
                .push(TUBE_FOOT + Vec3::new(c * TUBE_RADIUS, y, s * TUBE_RADIUS));
            lump.normals.push(Vec3::new(c, 0.0, s));
            lump.uvs.push([u, v]);
            skinning.joints.push([below, below + 1, 0, 0]);
            skinning.weights.push([1.0 - up, up, 0.0, 0.0]);
        }
    }
    let at = |ring: u32, j: u32| ring * (TUBE_AROUND + 1) + j;
    for ring in 0..TUBE_RINGS - 1 {
        for j in 0..TUBE_AROUND {
            let (a, b, c, d) = (
                at(ring, j),
                at(ring + 1, j),
                at(ring + 1, j + 1),
                at(ring, j + 1),
            );
            lump.indices.extend([a, b, c, a, c, d]);
        }
    }
    (lump, skinning)
}

/// The base colour textures: a checker, value noise and stripes, each [`TEXTURE_SIZE`] square,
/// light enough that the material's colour shows, as PNG files.
fn textures() -> std::io::Result<Vec<Vec<u8>>> {
    let n = TEXTURE_SIZE;
    let mut rng = SplitMix(0x7e57);
    let noise: Vec<f32> = (0..64).map(|_| rng.next_f32()).collect();
    let patterns: [&dyn Fn(u32, u32) -> f32; 3] = [
        &|x, y| if (x / 8 + y / 8) % 2 == 0 { 1.0 } else { 0.55 },
        // 8 x 8 random values, bilinear between them
        &|x, y| {
            let (fx, fy) = (x as f32 / 8.0, y as f32 / 8.0);
            let (x0, y0) = (fx.floor() as usize, fy.floor() as usize);
            let (tx, ty) = (fx.fract(), fy.fract());
            let v = |i: usize, j: usize| noise[(j % 8) * 8 + i % 8];
            let top = v(x0, y0) * (1.0 - tx) + v(x0 + 1, y0) * tx;
            let bottom = v(x0, y0 + 1) * (1.0 - tx) + v(x0 + 1, y0 + 1) * tx;
            0.5 + 0.5 * (top * (1.0 - ty) + bottom * ty)
        },
        &|x, y| if (x + y) % 16 < 8 { 1.0 } else { 0.6 },
    ];
    patterns
        .iter()
        .map(|pattern| {
            let image = image::RgbImage::from_fn(n, n, |x, y| {
                let l = (pattern(x, y) * 255.0) as u8;
                image::Rgb([l, l, l])
            });
            let mut png = Vec::new();
            image
                .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
                .map_err(std::io::Error::other)?;
            Ok(png)
        })
        .collect()
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
    let pngs = textures()?;
    // the ground (0) plain, lumps' materials 1 to TEXTURED each with a texture in turn
    let materials: Vec<Value> = (0..8)
        .map(|m| {
            let c = [
                0.2 + 0.7 * rng.next_f32(),
                0.2 + 0.7 * rng.next_f32(),
                0.2 + 0.7 * rng.next_f32(),
            ];
            let mut pbr = json!({"baseColorFactor": [c[0], c[1], c[2], 1.0],
                                 "metallicFactor": 0.0, "roughnessFactor": 0.8});
            if (1..=TEXTURED).contains(&m) {
                pbr["baseColorTexture"] = json!({"index": (m - 1) % pngs.len()});
            }
            json!({ "pbrMetallicRoughness": pbr })
        })
        .collect();
    let images: Vec<Value> = pngs
        .iter()
        .map(|png| {
            views.push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": png.len()}));
            bin.extend_from_slice(png);
            bin.resize(bin.len().next_multiple_of(4), 0);
            json!({"bufferView": views.len() - 1, "mimeType": "image/png"})
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
    // the joints' inverse bind matrices (column-major): each joint's place taken away
    let inverse_binds: Vec<u8> = (0..3)
        .flat_map(|k| {
            let at = TUBE_FOOT + Vec3::Y * (k as f32 * TUBE_HEIGHT / 3.0);
            bevy::math::Mat4::from_translation(-at).to_cols_array()
        })
        .flat_map(f32::to_le_bytes)
        .collect();
    let inverse_binds = accessor(&inverse_binds, 3, "MAT4", 5126, json!({}));
    let mut add_mesh = |lump: &Lump, material: usize, skinning: Option<&Skinning>| {
        let Lump {
            positions,
            normals,
            uvs,
            indices,
        } = lump;
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
        let uv_bytes: Vec<u8> = uvs.iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
        let uv = accessor(&uv_bytes, uvs.len(), "VEC2", 5126, json!({}));
        let index_bytes: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let index = accessor(&index_bytes, indices.len(), "SCALAR", 5125, json!({}));
        let mut attributes = json!({"POSITION": position, "NORMAL": normal, "TEXCOORD_0": uv});
        if let Some(Skinning { joints, weights }) = skinning {
            let joint_bytes: Vec<u8> = joints
                .iter()
                .flatten()
                .flat_map(|j| j.to_le_bytes())
                .collect();
            let weight_bytes: Vec<u8> = weights
                .iter()
                .flatten()
                .flat_map(|w| w.to_le_bytes())
                .collect();
            attributes["JOINTS_0"] = json!(accessor(
                &joint_bytes,
                joints.len(),
                "VEC4",
                5123,
                json!({})
            ));
            attributes["WEIGHTS_0"] = json!(accessor(
                &weight_bytes,
                weights.len(),
                "VEC4",
                5126,
                json!({})
            ));
        }
        meshes.push(
            json!({"primitives": [{"attributes": attributes, "indices": index,
                                           "material": material}]}),
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
    let ground_mesh = add_mesh(
        &Lump {
            positions: g.to_vec(),
            normals: vec![Vec3::Y; 4],
            uvs: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
            indices: vec![0, 2, 1, 0, 3, 2],
        },
        0,
        None,
    );
    nodes.push(json!({"name": "ground", "mesh": ground_mesh}));
    let mut scene = LargeScene {
        triangles: 2,
        meshes: 1,
        nodes: 1,
        mover_triangles: 0,
        skinned_triangles: 0,
        images: images.len(),
        textured_materials: TEXTURED,
        materials: materials.len(),
    };
    let mut lump_index = 0;
    while scene.triangles < TRIANGLES {
        let slices = 32 + 2 * (rng.next_f32() * 20.0) as u32;
        let l = lump(&mut rng, slices);
        let material = 1 + (rng.next_f32() * 7.0) as usize;
        let mesh = add_mesh(&l, material, None);
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
    // the skinned tube (its node untransformed, as glTF's skinned meshes are placed by their
    // joints) and its joints, each above the one before
    let (tube, skinning) = tube();
    let tube_mesh = add_mesh(&tube, 1, Some(&skinning));
    scene.meshes += 1;
    scene.nodes += 1;
    scene.skinned_triangles = tube.indices.len() / 3;
    scene.triangles += scene.skinned_triangles;
    nodes.push(json!({"name": "skinned", "mesh": tube_mesh, "skin": 0}));
    let root_joint = nodes.len();
    let step = [0.0, TUBE_HEIGHT / 3.0, 0.0];
    nodes.push(
        json!({"name": "skin root", "translation": TUBE_FOOT.to_array(),
                      "children": [root_joint + 1]}),
    );
    nodes.push(json!({"name": BENDER, "translation": step, "children": [root_joint + 2]}));
    nodes.push(json!({"name": "skin tip", "translation": step}));
    let skins = json!([{"name": "skinned", "inverseBindMatrices": inverse_binds,
                        "joints": [root_joint, root_joint + 1, root_joint + 2]}]);
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
        // every node but the joints under the root joint
        "scenes": [{"nodes": (0..nodes.len())
            .filter(|&n| n != root_joint + 1 && n != root_joint + 2)
            .collect::<Vec<_>>()}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "images": images,
        "samplers": [{"magFilter": 9729, "minFilter": 9987, "wrapS": 10497, "wrapT": 10497}],
        "textures": (0..scene.images).map(|i| json!({"sampler": 0, "source": i}))
            .collect::<Vec<_>>(),
        "skins": skins,
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
