//! `raypath completions` and `raypath man` cover every subcommand.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a panic is the failure report

mod common;
use common::raypath;

const SUBCOMMANDS: [&str; 5] = ["info", "convert", "slam", "loop-closure", "register"];

#[test]
fn completion_scripts_name_every_subcommand() {
    for shell in ["bash", "zsh", "fish", "elvish", "powershell"] {
        let out = raypath(&["completions", shell]);
        assert!(out.status.success(), "{shell}");
        let script = String::from_utf8(out.stdout).unwrap();
        for sub in SUBCOMMANDS {
            assert!(script.contains(sub), "{shell} script lacks {sub}");
        }
    }
    let out = raypath(&["completions", "tcsh"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("tcsh"));
}

#[test]
fn man_pages_for_the_program_and_each_subcommand() {
    let out = raypath(&["man"]);
    assert!(out.status.success());
    let page = String::from_utf8(out.stdout).unwrap();
    assert!(
        page.starts_with(".ie") || page.contains(".TH raypath"),
        "{}",
        &page[..200]
    );
    let dir = tempfile::tempdir().unwrap();
    let out = raypath(&["man", "--out", dir.path().to_str().unwrap()]);
    assert!(out.status.success());
    for sub in SUBCOMMANDS {
        let path = dir.path().join(format!("raypath-{sub}.1"));
        assert!(path.exists(), "{} missing", path.display());
    }
    assert!(dir.path().join("raypath.1").exists());
}

/// Choices (methods, models, presets, fusion rules, …) are value enums: clap refuses an
/// unknown value with exit code 2 before any file is read, accepts the documented aliases,
/// and `--help` lists the values.
#[test]
fn choices_are_checked_and_listed_by_clap() {
    for (args, value) in [
        (&["polylines", "none.log", "--method", "hough"][..], "hough"),
        (
            &[
                "octree",
                "none.graph",
                "--resolution",
                "0.1",
                "--fusion",
                "x",
            ][..],
            "x",
        ),
    ] {
        let out = raypath(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains(&format!("invalid value '{value}'")) && err.contains("possible values"),
            "{args:?}: {err}"
        );
    }
    // An alias passes clap; the missing file is the error.
    let out = raypath(&[
        "register",
        "none.xyz",
        "none.xyz",
        "--kernel",
        "geman-mcclure",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !err.contains("invalid value") && err.contains("none.xyz"),
        "{err}"
    );

    let out = raypath(&["planes", "--help"]);
    assert!(out.status.success());
    let help = String::from_utf8(out.stdout).unwrap();
    for value in [
        "ppe",
        "msac",
        "peac",
        "synpeb-0.5",
        "segcomp",
        "kitti",
        "default",
    ] {
        assert!(help.contains(value), "{value} not in\n{help}");
    }
}
