//! The `hst_scene` example's own code renders the same picture as the command line's path for
//! the bundled scene file of the same scene (`quadray raytrace --scene
//! assets/scenes/example-hst.toml --shadows hst --nth 8`: load the file, `quadray_shadows::run`):
//! pixel for pixel, no tolerance (the two scenes are the same polygons, vertices and materials).

#[allow(dead_code)] // the example's `main`
#[path = "../examples/hst_scene.rs"]
mod example;

use quadray_shadows::scene::{Scene, assets_dir};

#[test]
fn the_example_renders_what_the_cli_renders_from_its_scene_file() {
    let built = example::scene().unwrap();
    let file = Scene::load(&assets_dir().join("scenes/example-hst.toml")).unwrap();
    assert_eq!(
        (built.faces.len(), built.vertices.len(), &built.materials),
        (file.faces.len(), file.vertices.len(), &file.materials)
    );
    let from_code = example::render(built).unwrap();
    let (from_file, report) = quadray_shadows::run(file, &example::options(), &|| {}).unwrap();
    assert_eq!(report.nth.used, Some(example::NTH as f64));
    let differing = from_code
        .pixels
        .iter()
        .zip(&from_file.pixels)
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(
        differing, 0,
        "pixels differ between the example and the file"
    );
    // Not an empty picture: shadows and lit floor give many distinct colours.
    let colours: std::collections::HashSet<_> = from_code.pixels.iter().collect();
    assert!(colours.len() > 200, "{} colours", colours.len());
    assert!(report.shadow_polygons > 0 && report.subschemes.shadow_volume > 0);
}
