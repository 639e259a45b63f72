//! The builtin look-alikes of the paper's four scenes, rebuilt procedurally with its polygon and
//! light counts, and the shape builders they are made of.

use super::{Camera, Light, Material, Scene};
use glam::{Affine3A, Vec2, Vec3};

impl Scene {
    /// A surface of revolution about the local y axis: `profile` is (radius, height), a zero
    /// radius is a single vertex on the axis (its faces become triangles).
    fn lathe(&mut self, profile: &[(f32, f32)], slices: u32, place: Affine3A, material: u32) {
        let rings: Vec<Vec<u32>> = profile
            .iter()
            .map(|&(r, y)| {
                if r == 0.0 {
                    vec![
                        self.add_vertex(place.transform_point3(Vec3::new(0.0, y, 0.0)));
                        slices as usize
                    ]
                } else {
                    (0..slices)
                        .map(|j| {
                            let a = j as f32 / slices as f32 * std::f32::consts::TAU;
                            self.add_vertex(place.transform_point3(Vec3::new(
                                r * a.cos(),
                                y,
                                -r * a.sin(),
                            )))
                        })
                        .collect()
                }
            })
            .collect();
        for w in rings.windows(2) {
            for j in 0..slices as usize {
                let k = (j + 1) % slices as usize;
                self.push_face(vec![w[0][j], w[0][k], w[1][k], w[1][j]], material);
            }
        }
    }

    /// A prism: 2-D `points` in the local xy plane extruded along z by `depth`. `pieces` are convex
    /// (counter-clockwise) index lists covering the outline, `outline` its boundary loop.
    fn extrude(
        &mut self,
        points: &[Vec2],
        pieces: &[Vec<u32>],
        outline: &[u32],
        depth: f32,
        place: Affine3A,
        material: u32,
    ) {
        let base = self.vertices.len() as u32;
        for z in [0.0, depth] {
            for p in points {
                self.add_vertex(place.transform_point3(p.extend(z)));
            }
        }
        let back = |i: u32| base + points.len() as u32 + i;
        for piece in pieces {
            self.push_face(piece.iter().rev().map(|&i| base + i).collect(), material);
            self.push_face(piece.iter().map(|&i| back(i)).collect(), material);
        }
        for (e, &i) in outline.iter().enumerate() {
            let j = outline[(e + 1) % outline.len()];
            self.push_face(vec![base + i, base + j, back(j), back(i)], material);
        }
    }

    /// A straight bar from `a` to `b` of the given width, extruded (6 faces).
    fn bar(&mut self, a: Vec2, b: Vec2, width: f32, depth: f32, place: Affine3A, material: u32) {
        let n = (b - a).perp().normalize() * (width * 0.5);
        let pts = [a - n, b - n, b + n, a + n];
        self.extrude(
            &pts,
            &[vec![0, 1, 2, 3]],
            &[0, 1, 2, 3],
            depth,
            place,
            material,
        );
    }

    pub(super) fn cuboid(&mut self, min: Vec3, max: Vec3, material: u32) {
        let e = max - min;
        let pts = [
            Vec2::ZERO,
            Vec2::new(e.x, 0.0),
            Vec2::new(e.x, e.y),
            Vec2::new(0.0, e.y),
        ];
        self.extrude(
            &pts,
            &[vec![0, 1, 2, 3]],
            &[0, 1, 2, 3],
            e.z,
            Affine3A::from_translation(min),
            material,
        );
    }

    /// `count` polygons of floor at height `y` over `[x0, x1] x [z0, z1]`: a checkerboard grid of
    /// tiles sharing vertices, and the few left over as strips of a back wall at `z0`.
    #[allow(clippy::too_many_arguments)]
    fn floor(
        &mut self,
        count: usize,
        x0: f32,
        x1: f32,
        z0: f32,
        z1: f32,
        y: f32,
        wall_height: f32,
        tiles: [u32; 2],
    ) {
        let cols = (count as f32).sqrt().floor().max(1.0) as usize;
        let rows = count / cols;
        let rest = count - rows * cols;
        let lerp = |a: f32, b: f32, t: usize, n: usize| a + (b - a) * t as f32 / n as f32;
        let base = self.vertices.len() as u32;
        for r in 0..=rows {
            for c in 0..=cols {
                self.add_vertex(Vec3::new(lerp(x0, x1, c, cols), y, lerp(z0, z1, r, rows)));
            }
        }
        let at = |r: usize, c: usize| base + (r * (cols + 1) + c) as u32;
        for r in 0..rows {
            for c in 0..cols {
                self.push_face(
                    vec![at(r, c), at(r + 1, c), at(r + 1, c + 1), at(r, c + 1)],
                    tiles[(r + c) % 2],
                );
            }
        }
        if rest > 0 {
            let wall: Vec<(u32, u32)> = (0..=rest)
                .map(|c| {
                    let x = lerp(x0, x1, c, rest);
                    (
                        self.add_vertex(Vec3::new(x, y, z0)),
                        self.add_vertex(Vec3::new(x, y + wall_height, z0)),
                    )
                })
                .collect();
            for c in 0..rest {
                self.push_face(
                    vec![wall[c].0, wall[c + 1].0, wall[c + 1].1, wall[c].1],
                    tiles[c % 2],
                );
            }
        }
    }
}

fn camera(position: Vec3, target: Vec3, fov_y_deg: f32) -> Camera {
    Camera {
        position,
        target,
        up: Vec3::Y,
        fov_y_deg,
    }
}

fn at(x: f32, y: f32, z: f32) -> Affine3A {
    Affine3A::from_translation(Vec3::new(x, y, z))
}

/// Four lathed wine glasses (closed, thick, transparent) on a checkered floor: 3,781 polygons,
/// 3 lights.
pub(super) fn glasses() -> Scene {
    let mut s = Scene::new(
        "glasses",
        camera(Vec3::new(0.0, 3.0, 6.5), Vec3::new(0.0, 1.0, 0.0), 45.0),
    );
    let glass = s.add_material(Material::glass());
    let tiles = [
        s.add_material(Material::matte(Vec3::new(0.8, 0.75, 0.6))),
        s.add_material(Material::glossy(Vec3::new(0.25, 0.2, 0.3), 0.2)),
    ];
    // A closed profile from the foot's centre, out and up the outside, over the rim and down the
    // inside of the bowl back to the axis: 21 points, 20 segments.
    let profile = [
        (0.0, 0.0),
        (0.9, 0.0),
        (0.9, 0.06),
        (0.3, 0.1),
        (0.1, 0.2),
        (0.07, 0.5),
        (0.07, 0.9),
        (0.12, 1.1),
        (0.35, 1.22),
        (0.55, 1.4),
        (0.66, 1.7),
        (0.66, 2.0),
        (0.6, 2.3),
        (0.56, 2.3),
        (0.62, 2.0),
        (0.62, 1.7),
        (0.52, 1.43),
        (0.33, 1.27),
        (0.15, 1.18),
        (0.05, 1.15),
        (0.0, 1.14),
    ];
    // A hair above the floor: a refracted ray must meet every surface it passes through, which
    // a face lying on another (coplanar, touching) would hide.
    for (x, z) in [(-1.6, 0.3), (0.0, -0.6), (1.5, 0.5), (0.3, 1.6)] {
        s.lathe(&profile, 36, at(x, 0.002, z), glass);
    }
    s.floor(901, -4.0, 4.0, -4.0, 4.0, 0.0, 2.0, tiles);
    s.add_light(Light::white(Vec3::new(-3.0, 6.0, 3.0), 0.6));
    s.add_light(Light::white(Vec3::new(4.0, 5.0, 2.0), 0.5));
    s.add_light(Light::white(Vec3::new(0.5, 7.0, -3.0), 0.4));
    s
}

/// A desk with books, a lamp (with a light under its shade, inside the grid), a glass vase and a mirror
/// ball: 523 polygons, 3 lights.
pub(super) fn desk() -> Scene {
    let mut s = Scene::new(
        "desk",
        camera(Vec3::new(0.5, 3.2, 5.0), Vec3::new(0.0, 1.4, 0.0), 45.0),
    );
    let wood = s.add_material(Material::glossy(Vec3::new(0.55, 0.35, 0.2), 0.1));
    let books = [
        s.add_material(Material::matte(Vec3::new(0.7, 0.15, 0.1))),
        s.add_material(Material::matte(Vec3::new(0.1, 0.3, 0.6))),
        s.add_material(Material::matte(Vec3::new(0.2, 0.5, 0.2))),
    ];
    let metal = s.add_material(Material::glossy(Vec3::new(0.6, 0.6, 0.55), 0.3));
    let mirror = s.add_material(Material::glossy(Vec3::splat(0.2), 0.7));
    let glass = s.add_material(Material::glass());
    let tiles = [
        s.add_material(Material::matte(Vec3::new(0.6, 0.6, 0.6))),
        s.add_material(Material::matte(Vec3::new(0.35, 0.35, 0.4))),
    ];
    s.cuboid(Vec3::new(-2.0, 1.5, -1.0), Vec3::new(2.0, 1.6, 1.0), wood);
    for (x, z) in [(-1.9, -0.9), (1.8, -0.9), (-1.9, 0.8), (1.8, 0.8)] {
        s.cuboid(Vec3::new(x, 0.0, z), Vec3::new(x + 0.1, 1.5, z + 0.1), wood);
    }
    for (i, &m) in books.iter().enumerate() {
        let x = 0.6 + i as f32 * 0.25;
        s.cuboid(
            Vec3::new(x, 1.6, -0.6),
            Vec3::new(x + 0.2, 2.2 - 0.1 * i as f32, 0.1),
            m,
        );
    }
    // Lamp: base, arm and an open shade around the bulb (9 segments x 16 slices).
    let lamp = [
        (0.0, 0.0),
        (0.3, 0.0),
        (0.3, 0.05),
        (0.05, 0.1),
        (0.05, 0.7),
        (0.08, 0.75),
        (0.12, 0.8),
        (0.35, 0.75),
        (0.45, 0.55),
        (0.42, 0.55),
    ];
    s.lathe(&lamp, 16, at(-1.5, 1.6, -0.3), metal);
    // Vase (10 segments x 16 slices), closed and transparent.
    let vase = [
        (0.0, 0.0),
        (0.25, 0.0),
        (0.3, 0.2),
        (0.22, 0.5),
        (0.12, 0.65),
        (0.15, 0.8),
        (0.12, 0.8),
        (0.09, 0.65),
        (0.18, 0.5),
        (0.24, 0.2),
        (0.0, 0.04),
    ];
    s.lathe(&vase, 16, at(-0.5, 1.602, 0.4), glass); // a hair above the desk, as the glasses
    // Mirror ball (8 segments x 16 slices).
    let ball: Vec<(f32, f32)> = (0..=8)
        .map(|i| {
            let a = i as f32 / 8.0 * std::f32::consts::PI;
            (
                if i == 0 || i == 8 { 0.0 } else { 0.3 * a.sin() },
                0.3 - 0.3 * a.cos(),
            )
        })
        .collect();
    s.lathe(&ball, 16, at(0.2, 1.6, 0.3), mirror);
    s.floor(523 - s.faces.len(), -4.0, 4.0, -3.0, 3.0, 0.0, 3.0, tiles);
    s.add_light(Light::white(Vec3::new(-1.28, 2.2, -0.3), 0.5));
    s.add_light(Light::white(Vec3::new(3.0, 5.0, 2.5), 0.5));
    s.add_light(Light::white(Vec3::new(-3.0, 4.5, 2.0), 0.4));
    s
}

/// Five extruded five-pointed stars, tilted and floating over a floor: 113 polygons, 5 lights.
pub(super) fn stars() -> Scene {
    let mut s = Scene::new(
        "stars",
        camera(Vec3::new(0.0, 2.5, 7.0), Vec3::new(0.0, 1.5, 0.0), 50.0),
    );
    let colours = [
        Vec3::new(0.9, 0.7, 0.1),
        Vec3::new(0.8, 0.2, 0.2),
        Vec3::new(0.2, 0.6, 0.9),
        Vec3::new(0.3, 0.8, 0.3),
        Vec3::new(0.8, 0.4, 0.8),
    ];
    let mats: Vec<u32> = colours
        .iter()
        .map(|&c| s.add_material(Material::glossy(c, 0.3)))
        .collect();
    let tiles = [
        s.add_material(Material::matte(Vec3::new(0.7, 0.7, 0.7))),
        s.add_material(Material::matte(Vec3::new(0.4, 0.4, 0.45))),
    ];
    // Outline alternates outer points and inner corners; a pentagon and five triangles cover it.
    let points: Vec<Vec2> = (0..10)
        .map(|i| {
            let a = std::f32::consts::FRAC_PI_2 + i as f32 * std::f32::consts::PI / 5.0;
            Vec2::from_angle(a) * if i % 2 == 0 { 1.0 } else { 0.4 }
        })
        .collect();
    let mut pieces: Vec<Vec<u32>> = (0..5)
        .map(|i| vec![(2 * i + 9) % 10, 2 * i, 2 * i + 1])
        .collect();
    pieces.push(vec![1, 3, 5, 7, 9]);
    let outline: Vec<u32> = (0..10).collect();
    let places = [
        (Vec3::new(-2.6, 1.4, 0.0), 0.3),
        (Vec3::new(-0.9, 2.6, -1.0), -0.2),
        (Vec3::new(0.8, 1.3, 0.6), 0.6),
        (Vec3::new(2.5, 2.2, -0.5), -0.5),
        (Vec3::new(0.2, 3.6, -2.0), 0.1),
    ];
    for (&(pos, yaw), &m) in places.iter().zip(&mats) {
        let place = Affine3A::from_translation(pos)
            * Affine3A::from_rotation_y(yaw)
            * Affine3A::from_rotation_z(yaw * 0.7);
        s.extrude(&points, &pieces, &outline, 0.3, place, m);
    }
    s.floor(3, -5.0, 5.0, -4.0, 4.0, 0.0, 4.0, tiles);
    s.add_light(Light::white(Vec3::new(-4.0, 6.0, 4.0), 0.3));
    s.add_light(Light::white(Vec3::new(4.0, 6.0, 4.0), 0.3));
    s.add_light(Light::white(Vec3::new(0.0, 3.0, 2.0), 0.25));
    s.add_light(Light::white(Vec3::new(-3.0, 5.0, -3.0), 0.25));
    s.add_light(Light::white(Vec3::new(3.5, 2.0, -2.0), 0.25));
    s
}

/// The letters K, A, I, S, T extruded (the S swept along two arcs): 981 polygons, 4 lights.
pub(super) fn kaist() -> Scene {
    let mut s = Scene::new(
        "kaist",
        camera(Vec3::new(4.0, 3.0, 7.5), Vec3::new(4.0, 1.0, 0.0), 50.0),
    );
    let colours = [
        Vec3::new(0.15, 0.3, 0.8),
        Vec3::new(0.8, 0.3, 0.15),
        Vec3::new(0.2, 0.7, 0.3),
        Vec3::new(0.8, 0.75, 0.2),
        Vec3::new(0.6, 0.2, 0.7),
    ];
    let m: Vec<u32> = colours
        .iter()
        .map(|&c| s.add_material(Material::glossy(c, 0.25)))
        .collect();
    let tiles = [
        s.add_material(Material::matte(Vec3::new(0.75, 0.75, 0.7))),
        s.add_material(Material::glossy(Vec3::new(0.3, 0.3, 0.35), 0.3)),
    ];
    let v = Vec2::new;
    let (w, depth) = (0.35, 0.5);
    let place = |x: f32| Affine3A::from_translation(Vec3::new(x, 0.0, 0.0));
    // K
    s.bar(v(0.17, 0.0), v(0.17, 2.0), w, depth, place(0.0), m[0]);
    s.bar(v(0.3, 1.0), v(1.4, 2.0), w, depth, place(0.0), m[0]);
    s.bar(v(0.55, 1.2), v(1.45, 0.0), w, depth, place(0.0), m[0]);
    // A
    s.bar(v(0.15, 0.0), v(0.75, 2.0), w, depth, place(1.9), m[1]);
    s.bar(v(1.35, 0.0), v(0.75, 2.0), w, depth, place(1.9), m[1]);
    s.bar(v(0.4, 0.7), v(1.1, 0.7), 0.25, depth, place(1.9), m[1]);
    // I
    s.bar(v(0.17, 0.0), v(0.17, 2.0), w, depth, place(3.7), m[2]);
    // S: a strip swept along two arcs, 120 segments (4 * 120 + 2 faces).
    let segments = 120;
    let centre_line = |t: f32| -> (Vec2, Vec2) {
        // Upper arc counter-clockwise from 20 to 270 degrees, then the lower arc clockwise.
        if t < 0.5 {
            let a = (20.0 + 500.0 * t).to_radians();
            (
                v(0.5, 1.5) + Vec2::from_angle(a) * 0.5,
                v(-a.sin(), a.cos()),
            )
        } else {
            let a = (90.0 - 500.0 * (t - 0.5)).to_radians();
            (
                v(0.5, 0.5) + Vec2::from_angle(a) * 0.5,
                v(a.sin(), -a.cos()),
            )
        }
    };
    let mut points = Vec::new();
    for i in 0..=segments {
        let (c, tangent) = centre_line(i as f32 / segments as f32);
        points.push(c + tangent.perp() * 0.15);
    }
    for i in (0..=segments).rev() {
        let (c, tangent) = centre_line(i as f32 / segments as f32);
        points.push(c - tangent.perp() * 0.15);
    }
    let n = points.len() as u32;
    let pieces: Vec<Vec<u32>> = (0..segments as u32)
        .map(|i| vec![i, n - 1 - i, n - 2 - i, i + 1])
        .collect();
    let outline: Vec<u32> = (0..n).collect();
    s.extrude(
        &points,
        &pieces,
        &outline,
        depth,
        Affine3A::from_translation(Vec3::new(4.6, 0.15, 0.0)),
        m[3],
    );
    // T
    s.bar(v(0.7, 0.0), v(0.7, 1.85), w, depth, place(6.1), m[4]);
    s.bar(v(0.0, 1.85), v(1.4, 1.85), 0.3, depth, place(6.1), m[4]);
    s.floor(981 - s.faces.len(), -2.0, 10.0, -3.0, 4.0, 0.0, 3.0, tiles);
    s.add_light(Light::white(Vec3::new(-1.0, 5.0, 4.0), 0.35));
    s.add_light(Light::white(Vec3::new(8.0, 5.0, 4.0), 0.35));
    s.add_light(Light::white(Vec3::new(4.0, 2.6, 3.0), 0.3));
    s.add_light(Light::white(Vec3::new(4.0, 6.0, -2.5), 0.3));
    s
}
