//! `quadray scene`: what to do with a scene file besides rendering it.

use anyhow::{Context, Result};
use quadray_core::scene::SceneDescription;
use std::path::PathBuf;

/// `quadray scene`.
#[derive(clap::Args)]
pub struct SceneArgs {
    #[command(subcommand)]
    command: SceneCommand,
}

#[derive(clap::Subcommand)]
enum SceneCommand {
    /// Write a scene (TOML or glTF) as one glTF 2.0 file that `--scene` reads back as the same
    /// scene and Bevy's glTF loader shows: every object's triangles with matte materials, the
    /// camera, and the lights as KHR_lights_punctual (docs/scenes.md says what changes form).
    Export {
        /// The scene file: TOML, or glTF 2.0 (.gltf, .glb).
        scene: PathBuf,
        /// The glTF file to write (.gltf; its buffer embedded); its folder must exist.
        #[arg(value_parser = quadray_core::image_out::output_file(&[]))]
        out: PathBuf,
    },
}

pub fn run(args: SceneArgs) -> Result<()> {
    let SceneCommand::Export { scene, out } = args.command;
    let description = SceneDescription::load(&scene)?;
    // quadray indirect's builtin meshes are the only ones a scene file can name
    let description = quadray_indirect::scene::builtins_as_meshes(&description)
        .map_err(|e| anyhow::anyhow!("{}: {e}", scene.display()))?;
    description
        .save_gltf(&out)
        .with_context(|| format!("exporting {}", scene.display()))?;
    eprintln!("{}: {} written", scene.display(), out.display());
    Ok(())
}
