//! A small scene built in code and ray traced with hybrid shadow testing (HST): a floor and a
//! back wall, two boxes, a triangular prism, a mirror, two point lights. Writes
//! `out/examples/hst_scene.png` under the workspace root, or the PNG file given as its argument:
//!
//! ```text
//! cargo run --release -p quadray-shadows --example hst_scene [-- PICTURE.png]
//! ```
//!
//! The same scene as a scene file is `assets/scenes/example-hst.toml`; from the workspace root,
//! `quadray raytrace --scene assets/scenes/example-hst.toml --shadows hst --nth 8 --size 320x240`
//! renders the same picture.

use glam::Vec3;
use quadray_core::image_out::Rgba8Image;
use quadray_shadows::{
    BuildError, Camera, Light, Material, Nth, Scene, SchemeChoice, Settings, Size,
};
use std::path::{Path, PathBuf};

/// HST's threshold N_th, fixed so that the picture does not depend on timing (`Nth::Auto`
/// predicts it from the cost model and pilot renders).
const NTH: f32 = 8.0;

/// The scene: materials, lights, then the objects.
fn scene() -> Result<Scene, BuildError> {
    let camera = Camera {
        position: Vec3::new(0.5, 2.2, 5.0),
        target: Vec3::new(0.0, 0.6, 0.0),
        up: Vec3::Y,
        fov_y_deg: 45.0,
    };
    let mut s = Scene::new("example hst", camera);
    let blue = s.add_material(Material::glossy(Vec3::new(0.15, 0.3, 0.8), 0.2));
    let floor = s.add_material(Material::matte(Vec3::new(0.75, 0.72, 0.65)));
    let mirror = s.add_material(Material::glossy(Vec3::splat(0.1), 0.85));
    let red = s.add_material(Material::matte(Vec3::new(0.8, 0.2, 0.1)));
    s.add_light(Light::white(Vec3::new(2.0, 4.0, 2.5), 0.6));
    s.add_light(Light::white(Vec3::new(-2.5, 3.0, 1.5), 0.4));

    // Floor and back wall share their common edge (two vertices).
    let v = |s: &mut Scene, x: f32, y: f32, z: f32| s.add_vertex(Vec3::new(x, y, z));
    let corners = [
        v(&mut s, -3.0, 0.0, -2.0),
        v(&mut s, -3.0, 0.0, 3.0),
        v(&mut s, 3.0, 0.0, 3.0),
        v(&mut s, 3.0, 0.0, -2.0),
        v(&mut s, 3.0, 3.0, -2.0),
        v(&mut s, -3.0, 3.0, -2.0),
    ];
    s.add_face(corners[0..4].to_vec(), floor)?;
    s.add_face(vec![corners[0], corners[3], corners[4], corners[5]], floor)?;

    s.add_box(Vec3::new(-1.6, 0.0, -0.6), Vec3::new(-0.8, 1.2, 0.2), red)?;
    s.add_box(Vec3::new(0.9, 0.0, 0.2), Vec3::new(1.5, 0.6, 0.8), blue)?;

    // A triangular prism lying along z: the front triangle, three sides and the back triangle,
    // sharing 6 vertices (each face counter-clockwise seen from outside).
    let (a, b, c) = ((-0.4, 0.0), (0.4, 0.0), (0.0, 0.7));
    let mut end = |z: f32| [a, b, c].map(|(x, y)| v(&mut s, x, y, z));
    let (front, back) = (end(1.2), end(0.4));
    s.add_face(front.to_vec(), red)?;
    for i in 0..3 {
        let j = (i + 1) % 3;
        s.add_face(vec![front[j], front[i], back[i], back[j]], red)?;
    }
    s.add_face(vec![back[0], back[2], back[1]], red)?;

    // A mirror leaning on the back wall, facing the camera.
    let glass = [
        (-0.6, 0.2, -1.9),
        (0.6, 0.2, -1.9),
        (0.6, 1.8, -1.7),
        (-0.6, 1.8, -1.7),
    ];
    let ids = glass.map(|(x, y, z)| v(&mut s, x, y, z));
    s.add_face(ids.to_vec(), mirror)?;
    Ok(s)
}

/// How it is rendered: HST at [`NTH`], 320 x 240, reflections to depth 5 (the default).
fn settings() -> Settings {
    Settings {
        scheme: SchemeChoice::Hst,
        nth: Nth::Fixed(NTH),
        size: Size::new(320, 240),
        ..Settings::DEFAULT
    }
}

/// The picture of `scene` rendered with [`settings`].
fn render(scene: Scene) -> Result<Rgba8Image, BuildError> {
    let (image, report) = quadray_shadows::run(scene, &settings(), &|| {})?;
    let shares = &report.subschemes;
    println!(
        "{} polygons, {} shadow polygons; decisions: {} sustained, {} self-shadowed, {} by \
         shadow volume, {} by shadow ray",
        report.polygons,
        report.shadow_polygons,
        shares.sustain,
        shares.self_shadow,
        shares.shadow_volume,
        shares.conventional
    );
    Ok(image)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let image = render(scene()?)?;
    let out = std::env::args_os().nth(1).map_or_else(
        || Path::new(env!("CARGO_MANIFEST_DIR")).join("../../out/examples/hst_scene.png"),
        PathBuf::from,
    );
    image.save_png(&out)?;
    println!("wrote {}", out.display());
    Ok(())
}
