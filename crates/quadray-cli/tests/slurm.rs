//! The Slurm deployment on a real cluster: a one-node Slurm (Debian's slurm-wlm, installed by
//! scripts/setup.sh) sized to this machine, with its own munge key and socket, ports, state and
//! spool in a temporary folder. `deploy/slurm/submit.sh` runs as its header says; the merged
//! frames must be byte for byte the one-process renders; a failing item must cancel the merge and
//! `submit.sh --resume` must re-run exactly that item. The daemons are stopped however the test
//! ends.

use crate::common;

use std::fs::File;
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// What the deployment renders: a small turntable, two frames of three bands each.
const RENDER: &str = "--builtin stars --size 48x36 --spp 2 --orbit 35 --frames 1..3";
const TILES: u32 = 3;
/// How long a submission may take from sbatch to the merge's end.
const JOB_TIMEOUT: Duration = Duration::from_secs(180);

/// A running one-node cluster; dropping it cancels its jobs and stops its daemons.
struct Cluster {
    dir: PathBuf,
    conf: PathBuf,
    daemons: Vec<(&'static str, Child)>,
}

impl Cluster {
    fn start(dir: &Path) -> Cluster {
        for daemon in ["munged", "slurmctld", "slurmd"] {
            let found = Command::new(daemon).arg("-V").output();
            assert!(
                found.is_ok_and(|o| o.status.success()),
                "{daemon} is not installed: run scripts/setup.sh (it installs slurm-wlm and munge)"
            );
        }
        let uid = command_stdout(Command::new("id").arg("-u"));
        assert_eq!(
            uid.trim(),
            "0",
            "the Slurm test starts slurmd, which runs jobs as their users: run it as root"
        );
        let dir = dir.join("cluster");
        for sub in ["state", "spool"] {
            std::fs::create_dir_all(dir.join(sub)).unwrap();
        }
        let key = dir.join("munge.key");
        let mut urandom = File::open("/dev/urandom").unwrap();
        let mut bytes = vec![0u8; 1024];
        std::io::Read::read_exact(&mut urandom, &mut bytes).unwrap();
        std::fs::write(&key, bytes).unwrap();
        std::fs::set_permissions(&key, std::os::unix::fs::PermissionsExt::from_mode(0o400))
            .unwrap();
        let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
        let meminfo = std::fs::read_to_string("/proc/meminfo").unwrap();
        let total_kib: u64 = meminfo
            .lines()
            .find_map(|l| l.strip_prefix("MemTotal:"))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
            .expect("MemTotal in /proc/meminfo");
        // Below what slurmd measures, or it would drain the node for low memory.
        let memory_mib = total_kib / 1024 * 9 / 10;
        let host = std::fs::read_to_string("/proc/sys/kernel/hostname").unwrap();
        let host = host.trim().split('.').next().unwrap();
        // Two free ports: bound to port 0 together, so that they differ, then freed.
        let listeners = [(); 2].map(|_| TcpListener::bind("127.0.0.1:0").unwrap());
        let [ctld_port, slurmd_port] = listeners.map(|l| l.local_addr().unwrap().port());
        let d = dir.display();
        let conf = dir.join("slurm.conf");
        std::fs::write(
            &conf,
            format!(
                "ClusterName=quadraytest\n\
                 SlurmctldHost={host}\n\
                 SlurmctldPort={ctld_port}\n\
                 SlurmdPort={slurmd_port}\n\
                 AuthType=auth/munge\n\
                 CredType=cred/munge\n\
                 AuthInfo=socket={d}/munge.sock\n\
                 SlurmUser=root\n\
                 SlurmdUser=root\n\
                 StateSaveLocation={d}/state\n\
                 SlurmdSpoolDir={d}/spool\n\
                 SlurmctldPidFile={d}/slurmctld.pid\n\
                 SlurmdPidFile={d}/slurmd.pid\n\
                 SlurmctldLogFile={d}/slurmctld.log\n\
                 SlurmdLogFile={d}/slurmd.log\n\
                 MailProg=/bin/true\n\
                 ProctrackType=proctrack/linuxproc\n\
                 TaskPlugin=task/none\n\
                 SelectType=select/cons_tres\n\
                 SelectTypeParameters=CR_CPU\n\
                 SchedulerParameters=sched_interval=1,bf_interval=1\n\
                 MpiDefault=none\n\
                 ReturnToService=2\n\
                 JobAcctGatherType=jobacct_gather/none\n\
                 AccountingStorageType=accounting_storage/none\n\
                 MinJobAge=3600\n\
                 NodeName=quadraynode NodeAddr=127.0.0.1 CPUs={cpus} RealMemory={memory_mib} \
                 State=UNKNOWN\n\
                 PartitionName=main Nodes=ALL Default=YES MaxTime=INFINITE State=UP\n"
            ),
        )
        .unwrap();
        let mut cluster = Cluster {
            dir: dir.clone(),
            conf: conf.clone(),
            daemons: Vec::new(),
        };
        let path = |p: &str| dir.join(p).to_str().unwrap().to_string();
        cluster.spawn(
            "munged",
            &[
                "-F",
                "--force",
                &format!("--socket={}", path("munge.sock")),
                &format!("--key-file={}", path("munge.key")),
                &format!("--pid-file={}", path("munged.pid")),
                &format!("--log-file={}", path("munged.log")),
                &format!("--seed-file={}", path("munge.seed")),
            ],
        );
        cluster.wait_for("munged's socket", || dir.join("munge.sock").exists());
        let conf = path("slurm.conf");
        cluster.spawn("slurmctld", &["-D", "-c", "-f", &conf]);
        cluster.spawn("slurmd", &["-D", "-f", &conf, "-N", "quadraynode"]);
        cluster.wait_for("the node to be idle", || {
            let sinfo = cluster.command("sinfo").args(["-h", "-o", "%T"]).output();
            sinfo.is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "idle")
        });
        println!(
            "cluster: one node, {cpus} CPUs, {memory_mib} MiB, slurmctld port {ctld_port}, \
             slurmd port {slurmd_port}, in {d}"
        );
        cluster
    }

    fn spawn(&mut self, daemon: &'static str, args: &[&str]) {
        let log = File::create(self.dir.join(format!("{daemon}.out"))).unwrap();
        let child = Command::new(daemon)
            .args(args)
            .stdin(Stdio::null())
            .stdout(log.try_clone().unwrap())
            .stderr(log)
            .spawn()
            .unwrap_or_else(|e| panic!("cannot start {daemon}: {e}"));
        self.daemons.push((daemon, child));
    }

    /// `program` run against this cluster, the `quadray` under test on its PATH.
    fn command(&self, program: &str) -> Command {
        let bin = Path::new(env!("CARGO_BIN_EXE_quadray")).parent().unwrap();
        let path = std::env::var("PATH").unwrap_or_default();
        let mut command = Command::new(program);
        command
            .env("SLURM_CONF", &self.conf)
            .env("PATH", format!("{}:{path}", bin.display()))
            .env("RUST_BACKTRACE", "0");
        command
    }

    /// Polls `ready` every quarter second for a minute; fails with the cluster's state.
    fn wait_for(&self, what: &str, ready: impl Fn() -> bool) {
        let start = Instant::now();
        while !ready() {
            if start.elapsed() > Duration::from_secs(60) {
                panic!("waited a minute for {what}\n{}", self.diagnostics(None));
            }
            std::thread::sleep(Duration::from_millis(250));
        }
    }

    /// Waits until none of `jobs` is pending or running any more.
    fn wait_done(&self, jobs: &[&str], work: &Path) -> Duration {
        let start = Instant::now();
        let list = jobs.join(",");
        loop {
            let active = command_stdout(self.command("squeue").args(["-h", "-j", &list]));
            if active.trim().is_empty() {
                return start.elapsed();
            }
            if start.elapsed() > JOB_TIMEOUT {
                panic!(
                    "jobs {list} still pending or running after {JOB_TIMEOUT:?}:\n{active}\n{}",
                    self.diagnostics(Some(work))
                );
            }
            std::thread::sleep(Duration::from_millis(500));
        }
    }

    /// `squeue --states=all` of `job`: "ID STATE REASON" a line, array items included.
    fn states(&self, job: &str) -> String {
        command_stdout(self.command("squeue").args([
            "-h",
            "--states=all",
            "-j",
            job,
            "-o",
            "%i %T %r",
        ]))
    }

    /// `scontrol show job`'s JobState and Reason of `job`.
    fn job_state(&self, job: &str) -> String {
        let show = command_stdout(self.command("scontrol").args(["show", "job", job]));
        show.split_whitespace()
            .filter(|w| w.starts_with("JobState=") || w.starts_with("Reason="))
            .collect::<Vec<_>>()
            .join(" ")
    }

    /// The queue, every job, the node, the jobs' logs and the daemons' last lines.
    fn diagnostics(&self, work: Option<&Path>) -> String {
        let mut text = String::new();
        for args in [
            &["squeue", "--states=all"][..],
            &["scontrol", "show", "job"],
            &["sinfo", "-N", "-l"],
            &["sacct", "-a"],
        ] {
            let out = self.command(args[0]).args(&args[1..]).output();
            let out = out.map_or_else(
                |e| e.to_string(),
                |o| {
                    String::from_utf8_lossy(&o.stdout).to_string()
                        + &String::from_utf8_lossy(&o.stderr)
                },
            );
            text += &format!("--- {}\n{out}\n", args.join(" "));
        }
        let logs = work.map(|w| w.join("logs"));
        let mut files: Vec<PathBuf> = logs
            .and_then(|l| std::fs::read_dir(l).ok())
            .into_iter()
            .flatten()
            .filter_map(|e| e.ok().map(|e| e.path()))
            .collect();
        files.sort();
        for daemon in ["slurmctld", "slurmd", "munged"] {
            files.push(self.dir.join(format!("{daemon}.out")));
        }
        for file in files {
            let content = std::fs::read_to_string(&file).unwrap_or_default();
            let lines: Vec<&str> = content.lines().collect();
            let tail = lines[lines.len().saturating_sub(30)..].join("\n");
            text += &format!("--- {}\n{tail}\n", file.display());
        }
        text
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        if self.daemons.len() == 3 {
            // Jobs still queued or running (a failed test) would leave slurmstepd behind.
            let _ = self.command("scancel").args(["-u", "root"]).status();
            std::thread::sleep(Duration::from_secs(1));
        }
        while let Some((_, mut child)) = self.daemons.pop() {
            let _ = Command::new("kill")
                .args(["-TERM", &child.id().to_string()])
                .status();
            let start = Instant::now();
            while child.try_wait().ok().flatten().is_none() {
                if start.elapsed() > Duration::from_secs(5) {
                    let _ = child.kill();
                    let _ = child.wait();
                    break;
                }
                std::thread::sleep(Duration::from_millis(100));
            }
        }
    }
}

/// stdout of a command that must succeed.
fn command_stdout(command: &mut Command) -> String {
    let out = command
        .output()
        .unwrap_or_else(|e| panic!("{command:?}: {e}"));
    assert!(
        out.status.success(),
        "{command:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// The number after `label` in `text` ("array job 12," gives 12 for "array job").
fn number_after<'t>(text: &'t str, label: &str) -> &'t str {
    let rest = text
        .split_once(label)
        .unwrap_or_else(|| panic!("no {label:?} in {text}"))
        .1;
    let rest = rest.trim_start();
    let end = rest
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(rest.len());
    rest[..end].trim_end_matches('.')
}

/// Runs `deploy/slurm/submit.sh` in `dir` with the deployment's settings and `args`; gives its
/// output, the array job's id (if it submitted one) and the merge job's.
fn submit(cluster: &Cluster, dir: &Path, args: &[&str]) -> (String, Option<String>, String) {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../deploy/slurm/submit.sh");
    let out = command_stdout(
        cluster
            .command(script.to_str().unwrap())
            .args(args)
            .current_dir(dir)
            .env("RENDER", RENDER)
            .env("TILES", TILES.to_string())
            .env("OUT", "frames/turn.png")
            .env("WORK", "tiles")
            .env("CPUS", "1"),
    );
    println!("{out}");
    let array = out
        .contains("array job")
        .then(|| number_after(&out, "array job").to_string());
    let merge = number_after(&out, "merge job").to_string();
    (out, array, merge)
}

/// A picture that is not one colour: a merge of blank tiles would match a blank render too.
fn assert_not_uniform(path: &Path) {
    let picture = image::open(path).unwrap().to_rgba8();
    let first = picture.get_pixel(0, 0);
    assert!(
        picture.pixels().any(|p| p != first),
        "{} is one colour",
        path.display()
    );
}

#[test]
fn a_tiled_turntable_runs_on_slurm_fails_cleanly_and_resumes() {
    let dir = common::scratch("slurm");
    let cluster = Cluster::start(&dir);
    let items = 2 * TILES;

    // As the header says: N_th once, the array of items, the merge.
    let clean = dir.join("clean");
    std::fs::create_dir_all(&clean).unwrap();
    let started = Instant::now();
    let (out, array, merge) = submit(&cluster, &clean, &["--time=10"]);
    let array = array.expect("an array job");
    let nth = number_after(&out, "N_th").to_string();
    assert!(out.contains(&format!("items 0-{}", items - 1)), "{out}");
    cluster.wait_done(&[&array, &merge], &clean.join("tiles"));
    let wall = started.elapsed();
    let states = cluster.states(&array);
    println!("{states}");
    assert_eq!(
        states.matches(" COMPLETED ").count(),
        items as usize,
        "{states}"
    );
    assert_eq!(cluster.job_state(&merge), "JobState=COMPLETED Reason=None");
    // The extra sbatch option reached both jobs.
    for job in [format!("{array}_0"), merge.clone()] {
        let show = command_stdout(cluster.command("scontrol").args(["show", "job", &job]));
        assert!(show.contains("TimeLimit=00:10:00"), "{job}: {show}");
    }
    let log =
        std::fs::read_to_string(clean.join(format!("tiles/logs/tile-{array}_4.out"))).unwrap();
    assert!(log.contains("100% (") && log.contains("1 CPUs"), "{log}");

    // The job's own RENDER with --frame F and its N_th renders frame F in one process.
    for frame in [1, 2] {
        let one = dir.join(format!("one.{frame}.png"));
        let mut args: Vec<&str> = vec!["raytrace"];
        args.extend(RENDER.split_whitespace());
        let frame_text = frame.to_string();
        args.extend(["--frame", &frame_text, "--nth", &nth]);
        args.extend(["--out", one.to_str().unwrap()]);
        common::quadray_ok(&args);
        let merged = clean.join(format!("frames/turn.000{frame}.png"));
        assert!(
            std::fs::read(&one).unwrap() == std::fs::read(&merged).unwrap(),
            "{} differs from {}",
            merged.display(),
            one.display()
        );
        assert_not_uniform(&merged);
    }
    println!(
        "{items} items and the merge in {:.1}s on Slurm, N_th {nth}: both frames byte-identical \
         to one-process renders",
        wall.as_secs_f64()
    );

    // Item 4 (frame 2, tile 1) cannot write its tile: it fails, and the merge is cancelled
    // instead of waiting forever.
    let broken = dir.join("broken");
    let blocker = broken.join("tiles/frame0002-tile0001.exr.part");
    std::fs::create_dir_all(&blocker).unwrap();
    let (out, array, merge) = submit(&cluster, &broken, &[]);
    let array = array.expect("an array job");
    let broken_nth = number_after(&out, "N_th").to_string();
    let tiles = broken.join("tiles");
    cluster.wait_done(&[&array, &merge], &tiles);
    let states = cluster.states(&array);
    println!("after a failing item, squeue --states=all:\n{states}");
    assert!(
        states.contains(&format!("{array}_4 FAILED NonZeroExitCode")),
        "{states}"
    );
    assert_eq!(states.matches(" COMPLETED ").count(), items as usize - 1);
    let merge_state = cluster.states(&merge);
    println!("{merge_state}");
    assert_eq!(
        merge_state.trim(),
        format!("{merge} CANCELLED DependencyNeverSatisfied")
    );
    assert!(!broken.join("frames/turn.0002.png").exists());
    let log = std::fs::read_to_string(tiles.join(format!("logs/tile-{array}_4.out"))).unwrap();
    assert!(log.contains("cannot write the EXR"), "{log}");
    let tiles_arg = tiles.to_str().unwrap();
    common::quadray_refuses(
        &["merge", tiles_arg, "--out", "x.png"],
        "1 of 6 items missing: frame 2 tile 1 (item 4)",
    );
    let missing = command_stdout(
        cluster
            .command("quadray")
            .args(["tiles", "missing", tiles_arg]),
    );
    assert_eq!(missing, "4\n");

    // Fixed, the resume re-runs item 4 alone with the recorded settings, then merges.
    std::fs::remove_dir(&blocker).unwrap();
    let started = Instant::now();
    let (out, array, merge) = submit(&cluster, &broken, &["--resume", "tiles"]);
    let array = array.expect("an array job for the missing item");
    // The resume reuses the recorded N_th (each submission measures its own).
    assert!(
        out.contains("items 4,") && out.contains(&format!("N_th {broken_nth},")),
        "{out}"
    );
    cluster.wait_done(&[&array, &merge], &tiles);
    let states = cluster.states(&array);
    assert_eq!(states.trim(), format!("{array}_4 COMPLETED None"));
    assert_eq!(cluster.job_state(&merge), "JobState=COMPLETED Reason=None");
    for frame in [1, 2] {
        let name = format!("frames/turn.000{frame}.png");
        assert!(
            std::fs::read(clean.join(&name)).unwrap() == std::fs::read(broken.join(&name)).unwrap(),
            "the resumed {name} differs"
        );
    }
    println!(
        "resume: item 4 and the merge in {:.1}s, frames byte-identical",
        started.elapsed().as_secs_f64()
    );
    let none = command_stdout(
        cluster
            .command("quadray")
            .args(["tiles", "missing", tiles_arg]),
    );
    assert_eq!(none, "");
}
