//! The deployment's files, checked offline with the tools scripts/setup.sh installs: the
//! Kubernetes manifests, as written and as `deploy/kubernetes/run.sh` fills them in, against the
//! API schemas kubernetes-validate bundles; the Dockerfile with hadolint; the shell scripts with
//! shellcheck; and the Indexed Job's pod command, run here, picking a resume's items.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn deploy() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../deploy")
}

/// Runs a checker that scripts/setup.sh installs; fails naming it when it is missing.
fn check(program: &str, args: &[&str]) -> Output {
    Command::new(program)
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("{program}: {e}; scripts/setup.sh installs it"))
}

fn assert_ok(what: &str, out: &Output) -> String {
    let text =
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{what}:\n{text}");
    text
}

/// run.sh --print with a turntable of 36 frames in 8 tiles on 4 CPUs.
fn print_manifests(image: Option<&str>) -> Output {
    let mut run = Command::new(deploy().join("kubernetes/run.sh"));
    run.arg("--print")
        .env(
            "RENDER",
            "--scene /assets/scenes/shadows-bunny.toml --size 1920x1080 --orbit 10 --frames 0..36",
        )
        .env("TILES", "8")
        .env("CPUS", "4")
        .env_remove("IMAGE");
    if let Some(image) = image {
        run.env("IMAGE", image);
    }
    run.output().expect("run deploy/kubernetes/run.sh")
}

#[test]
fn kubernetes_manifests_match_the_api_schemas() {
    let dir = deploy().join("kubernetes");
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "yaml"))
        .map(|p| p.to_str().unwrap().to_string())
        .collect();
    files.sort();
    assert_eq!(files.len(), 5, "{files:?}");
    let filled = print_manifests(Some("registry.example.com/team/quadray:1.2.3"));
    let manifests = assert_ok("run.sh --print", &filled);
    let printed = common::scratch("deploy-files").join("manifests.yaml");
    std::fs::write(&printed, &manifests).unwrap();
    files.push(printed.to_str().unwrap().to_string());
    let args: Vec<&str> = ["--strict"]
        .into_iter()
        .chain(files.iter().map(String::as_str))
        .collect();
    let report = assert_ok(
        "kubernetes-validate --strict",
        &check("kubernetes-validate", &args),
    );
    println!("{report}");
    // Five files of one resource each, and the six resources run.sh fills in.
    assert_eq!(
        report.matches(" passed for resource ").count(),
        11,
        "{report}"
    );
    // The settings reached the manifests: the items, the CPUs, the image, the render.
    assert!(manifests.contains("completions: 288\n"), "{manifests}");
    assert_eq!(manifests.matches("cpu: \"4\", memory").count(), 2);
    assert_eq!(
        manifests
            .matches("image: registry.example.com/team/quadray:1.2.3\n")
            .count(),
        4
    );
    assert!(manifests.contains("RENDER: \"--scene /assets/scenes/shadows-bunny.toml"));
    let refused = print_manifests(None);
    assert!(!refused.status.success());
    assert!(String::from_utf8_lossy(&refused.stderr).contains("IMAGE"));
}

#[test]
fn the_dockerfile_and_the_scripts_pass_their_linters() {
    let d = deploy();
    let path = |p: &str| d.join(p).to_str().unwrap().to_string();
    assert_ok(
        "hadolint deploy/Dockerfile",
        &check("hadolint", &[&path("Dockerfile")]),
    );
    let scripts = [
        path("slurm/submit.sh"),
        path("slurm/tile.sbatch"),
        path("slurm/merge.sbatch"),
        path("kubernetes/run.sh"),
        path("../scripts/gpu-tables.sh"),
        path("../scripts/test.sh"),
        path("../scripts/setup.sh"),
    ];
    let args: Vec<&str> = scripts.iter().map(String::as_str).collect();
    assert_ok("shellcheck", &check("shellcheck", &args));
}

/// The tiles Job's pod command, with /work a scratch folder: with a resume's ITEMS, the pod of
/// index 1 renders the second listed item; without, the item of its own index.
#[test]
fn the_indexed_jobs_pod_renders_its_item() {
    let manifest = std::fs::read_to_string(deploy().join("kubernetes/tiles-job.yaml")).unwrap();
    let script: String = manifest
        .split_once("- |\n")
        .expect("the pod's script")
        .1
        .lines()
        .take_while(|l| !l.trim_start().starts_with("resources:"))
        .map(|l| l.trim_start().to_string() + "\n")
        .collect();
    let work = common::scratch("deploy-pod");
    let script = script.replace("/work", work.to_str().unwrap());
    std::fs::write(work.join("nth.txt"), "4\n").unwrap();
    let bin = Path::new(env!("CARGO_BIN_EXE_quadray")).parent().unwrap();
    let pod = |index: &str, items: &str| {
        let out = Command::new("sh")
            .args(["-c", &script])
            .env(
                "PATH",
                format!("{}:{}", bin.display(), std::env::var("PATH").unwrap()),
            )
            .env(
                "RENDER",
                "--builtin stars --size 24x16 --orbit 20 --frames 0..3",
            )
            .env("TILES", "2")
            .env("ITEMS", items)
            .env("JOB_COMPLETION_INDEX", index)
            .env_remove("SLURM_ARRAY_TASK_ID")
            .output()
            .unwrap();
        assert_ok(&format!("pod {index} with ITEMS={items:?}"), &out)
    };
    let tiles = work.join("tiles");
    pod("1", "2 5");
    assert!(tiles.join("frame0002-tile0001.exr").exists());
    assert_eq!(
        std::fs::read_dir(&tiles).unwrap().count(),
        2,
        "a tile and its stats"
    );
    pod("3", "");
    assert!(tiles.join("frame0001-tile0001.exr").exists());
}
