//! The Slurm recipe end to end: a single-node cluster started on this machine
//! (scripts/slurm/local-cluster.sh) runs scripts/slurm/render-array.sh, a job array of 4 shards
//! asking for --gres=gpu:1 and a merge job after them, and the merged image equals a
//! single-process render byte for byte. CI sets RT_GPU_REQUIRE_SLURM=1 (it installs slurm-wlm
//! and munge, and runs as root); elsewhere the test is skipped without them.
#![cfg(feature = "cli")]

use crate::common;

use common::cli::{rt_gpu, stderr};
use std::path::{Path, PathBuf};
use std::process::Command;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Why this machine cannot start a cluster, if it cannot.
fn missing() -> Option<String> {
    let found = |program: &str| {
        Command::new("sh")
            .args(["-c", &format!("command -v {program}")])
            .output()
            .is_ok_and(|o| o.status.success())
    };
    for program in ["sbatch", "slurmctld", "slurmd", "munged"] {
        if !found(program) && !Path::new(&format!("/usr/sbin/{program}")).exists() {
            return Some(format!(
                "{program} is not installed (apt-get install slurm-wlm munge)"
            ));
        }
    }
    let uid = Command::new("id").arg("-u").output().ok()?;
    (String::from_utf8_lossy(&uid.stdout).trim() != "0")
        .then(|| "starting slurmd needs root".to_string())
}

/// Stops the cluster however the test ends.
struct Cluster(PathBuf);

impl Drop for Cluster {
    fn drop(&mut self) {
        let _ = Command::new("bash")
            .arg(repo().join("scripts/slurm/local-cluster.sh"))
            .arg("--stop")
            .arg(&self.0)
            .status();
    }
}

#[test]
fn a_slurm_job_array_of_shards_merges_into_the_single_render() {
    if let Some(why) = missing() {
        if std::env::var_os("RT_GPU_REQUIRE_SLURM").is_some() {
            panic!("RT_GPU_REQUIRE_SLURM is set but {why}");
        }
        eprintln!("skipping the Slurm test: {why}");
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let cluster_dir = d.join("cluster");
    // Ports of this run's own, clear of a cluster another run may have left.
    let port = 20000 + 2 * (std::process::id() % 10000);
    let started = Command::new("bash")
        .arg("-c")
        .arg("source \"$0\" \"$1\"")
        .arg(repo().join("scripts/slurm/local-cluster.sh"))
        .arg(&cluster_dir)
        .env("RT_GPU_SLURMCTLD_PORT", port.to_string())
        .env("RT_GPU_SLURMD_PORT", (port + 1).to_string())
        .output()
        .expect("runs");
    let _cluster = Cluster(cluster_dir.clone());
    assert!(started.status.success(), "{}", stderr(&started));

    let backend = if common::gpu::renderer().is_some() {
        "gpu"
    } else {
        "cpu"
    };
    let options = ["--size", "40x24", "--backend", backend, "--max-depth", "6"];
    let out = Command::new("bash")
        .arg(repo().join("scripts/slurm/render-array.sh"))
        .args(["cornell", "96", "4", "merged.pfm"])
        .args(options)
        .current_dir(d)
        .env("SLURM_CONF", cluster_dir.join("slurm.conf"))
        .env("RT_GPU", env!("CARGO_BIN_EXE_rt-gpu"))
        .env("FILMS", d.join("films"))
        .env("WAIT", "1")
        .output()
        .expect("runs");
    let logs = || {
        std::fs::read_dir(d.join("films"))
            .into_iter()
            .flatten()
            .flatten()
            .filter(|e| e.path().extension().is_some_and(|x| x == "log"))
            .map(|e| std::fs::read_to_string(e.path()).unwrap_or_default())
            .collect::<Vec<_>>()
            .join("\n")
    };
    assert!(out.status.success(), "{}\n{}", stderr(&out), logs());

    let single = [
        &["cornell", "--spp", "96", "-o", "single.pfm"][..],
        &options,
    ]
    .concat();
    let out = rt_gpu(&single, d);
    assert!(out.status.success(), "{}", stderr(&out));
    let read = |name: &str| std::fs::read(d.join(name)).expect("written");
    assert!(
        read("merged.pfm") == read("single.pfm"),
        "the merged shards differ from the single render\n{}",
        logs()
    );
}
