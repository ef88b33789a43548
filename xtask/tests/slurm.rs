//! The Slurm path of sharded evaluations, run for real: `slurm_localhost.sh` starts a
//! one-node Slurm cluster on localhost (Debian's slurm-wlm with munge), runs
//! `docs/cluster/run-slurm.sh carmen-angles 2 --quick` (a job array of two shards, then the
//! merge job) and compares the merged report with an unsharded run. Skips with a message
//! where Slurm is not installed or cannot start (`.ci/run` installs it).

use std::path::Path;
use std::process::Command;

#[test]
fn a_slurm_job_array_of_two_shards_merges_into_the_unsharded_report() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let script = root.join("xtask/tests/slurm_localhost.sh");
    let out = Command::new("bash")
        .arg(&script)
        .arg(env!("CARGO_BIN_EXE_xtask"))
        .arg(&root)
        .output()
        .expect("bash runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    match out.status.code() {
        Some(0) => println!("{stdout}"),
        Some(77) => raypath_io::data::skip(format_args!("Slurm test: {}", stdout.trim())),
        _ => panic!("{} failed:\n{stdout}\n{stderr}", script.display()),
    }
}
