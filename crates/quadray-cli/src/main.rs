//! `quadray`: renders each technique headless, compares it with its CPU ground truth, and runs the
//! benchmarks. Each subcommand lives in its own module.

mod bench;
mod raytrace;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "quadray", version, about = "Reference implementations of three rendering papers")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Print the GPU adapter quadray would use.
    Adapter,
    /// Whitted ray tracing on a uniform grid with hybrid shadow testing.
    Raytrace(raytrace::RaytraceArgs),
    /// Benchmarks that reproduce the papers' tables and figures.
    Bench(bench::BenchArgs),
}

fn main() -> anyhow::Result<()> {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "warn".into()),
        )
        .with_writer(std::io::stderr)
        .init();
    match Cli::parse().command {
        Command::Adapter => {
            let gpu = quadray_gpu::Gpu::new()?;
            println!("{}", gpu.describe());
        }
        Command::Raytrace(args) => raytrace::run(args)?,
        Command::Bench(args) => bench::run(args)?,
    }
    Ok(())
}
