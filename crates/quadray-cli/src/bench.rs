//! `quadray bench ...`: the benchmarks that reproduce the papers' tables and figures.

use std::path::PathBuf;

#[derive(clap::Args)]
pub struct BenchArgs {
    #[command(subcommand)]
    which: Which,
}

#[derive(clap::Subcommand)]
enum Which {
    /// Hybrid shadow testing: tables 1-4 and figure 6 of Eo & Kyung on the four look-alike scenes,
    /// with SAH BVH shadow rays as today's baseline.
    Shadows {
        /// Small images and one render per measurement.
        #[arg(long)]
        quick: bool,
        /// Output folder for results.json, shadows.md and the SVG plots.
        #[arg(long)]
        out: PathBuf,
    },
}

pub fn run(args: BenchArgs) -> anyhow::Result<()> {
    match args.which {
        Which::Shadows { quick, out } => {
            let results =
                quadray_shadows::bench::bench_shadows(quick, &out, &|msg| eprintln!("{msg}"))?;
            for s in &results.scenes {
                let (conv, hst, bvh) = (&s.schemes[0], &s.schemes[2], &s.schemes[3]);
                println!(
                    "{}: shadow hst/conventional {:.2}, total {:.2}, hst/bvh {:.2}; N_th predicted {:.1}, best {} (shadow at predicted / best {:.2})",
                    s.scene,
                    hst.shadow / conv.shadow,
                    hst.total / conv.total,
                    hst.shadow / bvh.shadow,
                    s.predicted_nth,
                    s.best_nth,
                    s.predicted_over_best
                );
            }
            println!("wrote {}", out.join("shadows.md").display());
        }
    }
    Ok(())
}
