//! quadray indirect's procedural meshes: the Cornell box (room and blocks) and a Sponza-like
//! atrium, as triangles with per-vertex albedo.

use super::Vertex;
use glam::{Mat4, Vec3};
use quadray_core::scene::Shape;

const WHITE: [f32; 3] = [0.73, 0.73, 0.73];
const RED: [f32; 3] = [0.63, 0.065, 0.05];
const GREEN: [f32; 3] = [0.14, 0.45, 0.091];

/// The triangles of builtin mesh `name`.
pub(super) fn builtin_triangles(name: &str) -> Result<Vec<[Vertex; 3]>, String> {
    Ok(match name {
        "cornell" => {
            let mut t = cornell_room();
            t.extend(cornell_blocks());
            t
        }
        "room" => cornell_room(),
        "blocks" => cornell_blocks(),
        "atrium" => atrium(),
        other => {
            return Err(format!(
                "unknown builtin `{other}` (known: cornell, room, blocks, atrium)"
            ));
        }
    })
}

/// Two triangles of the quad a, b, c, d (counter-clockwise seen from the side `normal` faces).
fn quad(a: Vec3, b: Vec3, c: Vec3, d: Vec3, albedo: [f32; 3]) -> [[Vertex; 3]; 2] {
    let normal = (b - a).cross(d - a).normalize();
    let v = |p: Vec3| Vertex::untextured(p.into(), normal.into(), albedo);
    [[v(a), v(b), v(c)], [v(a), v(c), v(d)]]
}

// The faces of a box seen from outside (the scene model's, in quad order).
const TOP: [usize; 4] = Shape::BOX_FACES[0];
const FRONT: [usize; 4] = Shape::BOX_FACES[2]; // +z
const BACK: [usize; 4] = Shape::BOX_FACES[3]; // -z
const LEFT: [usize; 4] = Shape::BOX_FACES[4]; // -x
const RIGHT: [usize; 4] = Shape::BOX_FACES[5]; // +x

/// The two triangles of each face, the face's corners numbered as in [`Shape::box_corner`].
fn box_faces(corners: [Vec3; 8], faces: &[([usize; 4], [f32; 3])]) -> Vec<[Vertex; 3]> {
    faces
        .iter()
        .flat_map(|&([a, b, c, d], albedo)| {
            quad(corners[a], corners[b], corners[c], corners[d], albedo)
        })
        .collect()
}

/// The unit room [0,1]^3 open towards +z: red wall at x = 0, green at x = 1.
fn cornell_room() -> Vec<[Vertex; 3]> {
    let corners = std::array::from_fn(|i| Shape::box_corner(Vec3::ZERO, Vec3::ONE, i));
    // seen from inside
    let floor = [4, 5, 1, 0];
    let ceiling = [2, 3, 7, 6];
    let back = [0, 1, 3, 2];
    let left = [4, 0, 2, 6];
    let right = [1, 5, 7, 3];
    box_faces(
        corners,
        &[
            (floor, WHITE),
            (ceiling, WHITE),
            (back, WHITE),
            (left, RED),
            (right, GREEN),
        ],
    )
}

/// The short and the tall block of the Cornell box, turned as in the original.
fn cornell_blocks() -> Vec<[Vertex; 3]> {
    let mut out = block(Vec3::new(0.66, 0.0, 0.62), 0.3, 0.3, -17.0);
    out.extend(block(Vec3::new(0.32, 0.0, 0.33), 0.3, 0.6, 17.0));
    out
}

/// An upright box of footprint `side` and `height` standing on y = 0 at `centre` (no bottom).
fn block(centre: Vec3, side: f32, height: f32, turn_deg: f32) -> Vec<[Vertex; 3]> {
    let r = Mat4::from_translation(centre) * Mat4::from_rotation_y(turn_deg.to_radians());
    let h = side * 0.5;
    let (lo, hi) = (Vec3::new(-h, 0.0, -h), Vec3::new(h, height, h));
    let corners = std::array::from_fn(|i| r.transform_point3(Shape::box_corner(lo, hi, i)));
    box_faces(
        corners,
        &[TOP, FRONT, RIGHT, BACK, LEFT].map(|f| (f, WHITE)),
    )
}

/// An axis-aligned box, faces outwards (the scene model's faces, which a box written to glTF
/// has too).
pub(super) fn cuboid(lo: Vec3, hi: Vec3, albedo: [f32; 3]) -> Vec<[Vertex; 3]> {
    Shape::box_faces(lo, hi)
        .into_iter()
        .flat_map(|[a, b, c, d]| quad(a, b, c, d, albedo))
        .collect()
}

/// A vertical cylinder (no caps) with smooth normals, `segments` around and `rings` high.
fn column(base: Vec3, radius: f32, height: f32, segments: u32, rings: u32) -> Vec<[Vertex; 3]> {
    let albedo = [0.75, 0.72, 0.66];
    let at = |i: u32, j: u32| {
        let a = std::f32::consts::TAU * i as f32 / segments as f32;
        let n = Vec3::new(a.cos(), 0.0, a.sin());
        Vertex::untextured(
            (base + n * radius + Vec3::Y * height * j as f32 / rings as f32).into(),
            n.into(),
            albedo,
        )
    };
    (0..segments)
        .flat_map(|i| (0..rings).map(move |j| (i, j)))
        .flat_map(|(i, j)| {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            [[a, c, b], [a, d, c]]
        })
        .collect()
}

/// A Sponza-like courtyard, 30 x 15 x 13 m, open to the sky: stone floor, two storeys of
/// galleries on columns along both long sides, coloured banners hanging between the columns.
fn atrium() -> Vec<[Vertex; 3]> {
    const STONE: [f32; 3] = [0.62, 0.57, 0.48];
    const PLASTER: [f32; 3] = [0.74, 0.68, 0.58];
    const BANNERS: [[f32; 3]; 3] = [[0.7, 0.08, 0.06], [0.08, 0.15, 0.6], [0.1, 0.5, 0.12]];
    let (length, width, height) = (30.0, 13.0, 15.0);
    let p = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let mut out: Vec<[Vertex; 3]> = Vec::new();
    out.extend(quad(
        p(0., 0., width),
        p(length, 0., width),
        p(length, 0., 0.),
        p(0., 0., 0.),
        STONE,
    ));
    out.extend(quad(
        p(0., 0., 0.),
        p(length, 0., 0.),
        p(length, height, 0.),
        p(0., height, 0.),
        PLASTER,
    ));
    out.extend(quad(
        p(length, 0., width),
        p(0., 0., width),
        p(0., height, width),
        p(length, height, width),
        PLASTER,
    ));
    out.extend(quad(
        p(0., 0., width),
        p(0., 0., 0.),
        p(0., height, 0.),
        p(0., height, width),
        PLASTER,
    ));
    out.extend(quad(
        p(length, 0., 0.),
        p(length, 0., width),
        p(length, height, width),
        p(length, height, 0.),
        PLASTER,
    ));
    for (side, z) in [(0.0f32, 3.0f32), (1.0, width - 3.0)] {
        let (z0, z1) = if side == 0.0 { (0.0, z) } else { (z, width) };
        for storey in 0..2 {
            let floor = 5.0 * (storey as f32 + 1.0);
            out.extend(cuboid(p(0.0, floor - 0.4, z0), p(length, floor, z1), STONE));
            for i in 0..12 {
                let x = 1.5 + 2.45 * i as f32;
                out.extend(column(p(x, floor - 5.0, z), 0.35, 4.6, 32, 8));
                if storey == 1 && i < 11 {
                    let banner = BANNERS[i % 3];
                    let (bz, x0, x1) =
                        (z + if side == 0.0 { 0.2 } else { -0.2 }, x + 0.5, x + 1.95);
                    out.extend(quad(
                        p(x0, 5.0, bz),
                        p(x1, 5.0, bz),
                        p(x1, 9.0, bz),
                        p(x0, 9.0, bz),
                        banner,
                    ));
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cornell_room_normals_face_inwards_and_blocks_outwards() {
        let centre = Vec3::new(0.5, 0.5, 0.5);
        for t in cornell_room() {
            let n = Vec3::from(t[0].normal);
            assert!(n.dot(centre - Vec3::from(t[0].position)) > 0.0);
        }
        let centre = Vec3::new(0.4, 0.0, 0.3);
        for t in block(centre, 0.3, 0.6, 17.0) {
            let mid =
                (Vec3::from(t[0].position) + Vec3::from(t[1].position) + Vec3::from(t[2].position))
                    / 3.0;
            let inside = centre + Vec3::new(0.0, 0.3, 0.0);
            assert!(Vec3::from(t[0].normal).dot(mid - inside) > 0.0);
        }
        let all = builtin_triangles("cornell").unwrap();
        assert_eq!(all.len(), 10 + 20);
    }
}
