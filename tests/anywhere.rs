//! The installed tool, as a user meets it outside any project: in an empty folder it runs the
//! profiles and corpus built into it, finds a project upward from a subfolder, says where it
//! looked when a folder is missing, and prints completion scripts and a manual page that parse.

mod common;

use std::path::Path;
use std::process::Output;

use common::{bin, root, scratch};

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Runs the binary in `dir` with no project named anywhere.
fn run_in(dir: &Path, args: &[&str]) -> Output {
    bin()
        .current_dir(dir)
        .args(args)
        .output()
        .expect("the binary runs")
}

#[test]
fn run_list_diff_and_an_external_backend_work_in_an_empty_folder() {
    let empty = scratch();
    let dir = empty.path();

    let out = run_in(dir, &["run"]);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}{}", text(&out.stderr));
    assert!(
        stdout
            .lines()
            .last()
            .is_some_and(|l| l.contains(" passed, 0 failed")),
        "{stdout}"
    );

    let out = run_in(dir, &["list"]);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(
        stdout.starts_with(
            "data: profiles <embedded>/vendors, vectors <embedded>/vectors, project file none\n"
        ),
        "{stdout}"
    );
    assert!(stdout.contains("habin-fixed-4-digits-example"), "{stdout}");

    let out = run_in(
        dir,
        &["diff", "--format", "html", "--output", "report.html"],
    );
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let html = std::fs::read_to_string(dir.join("report.html")).expect("report written");
    assert!(html.contains("<table class=\"matrix\""));

    // A backend of the user's, over the protocol: the served reference model.
    let out = run_in(
        dir,
        &[
            "run",
            "--backend",
            r#"external:my-emu="$PLC_CONFORMANCE" serve --profile mitsubishi-iqr"#,
            "--filter",
            "habin-fixed",
            "--format",
            "json",
        ],
    );
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    let records = report["records"].as_array().expect("records");
    assert!(!records.is_empty());
    for r in records {
        assert!(
            r["trial"].as_str().is_some_and(|t| t.contains("my-emu::")),
            "{r}"
        );
        assert!(
            r["file"]
                .as_str()
                .is_some_and(|f| f.starts_with("<embedded>/vectors/")),
            "{r}"
        );
    }
    // Nothing was written but the report asked for.
    let left: Vec<_> = std::fs::read_dir(dir)
        .expect("readable")
        .map(|e| e.expect("entry").file_name())
        .collect();
    assert_eq!(left, vec![std::ffi::OsString::from("report.html")]);
}

#[test]
fn the_built_in_files_are_named_under_embedded() {
    let empty = scratch();
    let out = run_in(
        empty.path(),
        &["validate", "<embedded>/vectors/mitsubishi-iqr/habin.yaml"],
    );
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    // Every built-in profile is loaded, and one file is one file.
    let profiles = std::fs::read_dir(root().join("vendors"))
        .expect("vendors/")
        .filter(|e| {
            e.as_ref()
                .is_ok_and(|e| e.path().extension().is_some_and(|x| x == "yaml"))
        })
        .count();
    assert!(
        stdout.contains(&format!(" in 1 file, {profiles} profiles")),
        "{stdout}"
    );
    let out = run_in(
        empty.path(),
        &["run", "--vectors", "<embedded>/vectors/nowhere"],
    );
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    assert!(
        err.contains("--vectors <embedded>/vectors/nowhere: no such file or folder"),
        "{err}"
    );
}

#[test]
fn a_project_is_found_upward_and_uses_the_built_in_data_it_lacks() {
    let project = scratch();
    let root = project.path();
    std::fs::write(
        root.join("plc-conformance.yaml"),
        "backends:\n  - name: my-emu\n    command: '\"$PLC_CONFORMANCE\" serve --profile idec-fc4a'\n    \
         profile: idec-fc4a\n",
    )
    .expect("project file");
    let sub = root.join("src/deep");
    std::fs::create_dir_all(&sub).expect("subfolder");
    let out = run_in(&sub, &["list"]);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(
        stdout.starts_with(
            "data: profiles <embedded>/vendors, vectors <embedded>/vectors, project file \
             ../../plc-conformance.yaml\n"
        ),
        "{stdout}"
    );
    assert!(stdout.contains("my-emu"), "{stdout}");
    let out = run_in(&sub, &["run", "--backend", "my-emu", "--filter", "atoh"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stdout));
    assert!(
        text(&out.stdout).contains("my-emu: "),
        "{}",
        text(&out.stdout)
    );
}

#[test]
fn a_root_that_is_no_project_says_where_it_looked_and_what_to_pass() {
    let empty = scratch();
    let dir = empty.path().to_str().unwrap_or_default().to_string();
    let out = run_in(empty.path(), &["--root", &dir, "run"]);
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    assert!(
        err.contains(&format!(
            "error: --root {dir}: not a plc-conformance project (looked for \
             {dir}/plc-conformance.yaml, and for {dir}/vendors/ with {dir}/vectors/)"
        )),
        "{err}"
    );
    assert!(
        err.contains("hint: pass the folder that holds them"),
        "{err}"
    );
    let out = run_in(empty.path(), &["run", "--vendors", "profiles"]);
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    assert!(
        err.contains(&format!(
            "error: --vendors profiles: no such folder (looked at {dir}/profiles)"
        )),
        "{err}"
    );
}

#[test]
fn the_bash_completion_script_parses() {
    let out = run_in(scratch().path(), &["completions", "bash"]);
    assert_eq!(out.status.code(), Some(0));
    let script = text(&out.stdout);
    assert!(script.contains("plc-conformance"), "{script}");
    for option in ["--backend", "--fail-fast", "--quiet", "--format"] {
        assert!(script.contains(option), "completion lacks {option}");
    }
    let dir = scratch();
    let file = dir.path().join("plc-conformance.bash");
    std::fs::write(&file, &script).expect("write");
    let check = std::process::Command::new("bash")
        .arg("-n")
        .arg(&file)
        .output()
        .expect("bash runs");
    assert!(check.status.success(), "{}", text(&check.stderr));
    for shell in ["zsh", "fish", "elvish", "powershell"] {
        let out = run_in(dir.path(), &["completions", shell]);
        assert_eq!(out.status.code(), Some(0), "{shell}");
        assert!(!out.stdout.is_empty(), "{shell}");
    }
}

#[test]
fn the_manual_page_parses() {
    let out = run_in(scratch().path(), &["man"]);
    assert_eq!(out.status.code(), Some(0));
    let page = text(&out.stdout);
    for section in [
        ".TH plc-conformance 1",
        ".SH NAME",
        ".SH SYNOPSIS",
        ".SH SUBCOMMANDS",
    ] {
        assert!(page.contains(section), "the page lacks {section}:\n{page}");
    }
    // groff, where installed, must format it without a warning.
    let groff = std::process::Command::new("groff")
        .args(["-man", "-Tutf8", "-ww", "-z"])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn();
    let Ok(mut groff) = groff else {
        eprintln!("groff is not installed: checked the page's structure only");
        return;
    };
    if let Some(mut stdin) = groff.stdin.take() {
        std::io::Write::write_all(&mut stdin, page.as_bytes()).expect("write to groff");
    }
    let done = groff.wait_with_output().expect("groff runs");
    assert!(done.status.success(), "{}", text(&done.stderr));
    assert!(
        done.stderr.is_empty(),
        "groff warns: {}",
        text(&done.stderr)
    );
}

/// A JUnit report names real files only (a dashboard opens them) and carries the run's time.
#[test]
fn junit_outside_a_project_names_no_embedded_file_and_times_the_run() {
    let empty = scratch();
    let out = run_in(
        empty.path(),
        &["run", "--backend", "iqr", "--format", "junit"],
    );
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let xml = text(&out.stdout);
    assert!(xml.contains("<testcase "), "{xml}");
    assert!(!xml.contains("file=\"&lt;embedded"), "{xml}");
    let time = xml
        .split("<testsuites ")
        .nth(1)
        .and_then(|t| t.split(" time=\"").nth(1))
        .and_then(|t| t.split('"').next())
        .and_then(|t| t.parse::<f64>().ok())
        .expect("the report's time");
    assert!(time > 0.0, "{xml}");
}

/// Every page the manual page names is written by `man --dir`.
#[test]
fn man_dir_writes_every_page_the_manual_names() {
    let out = run_in(scratch().path(), &["man"]);
    let page = text(&out.stdout);
    let named: Vec<String> = page
        .lines()
        .filter_map(|l| l.strip_suffix("(1)"))
        .map(|n| format!("{}.1", n.replace("\\-", "-")))
        .collect();
    assert!(named.len() >= 8, "{page}");
    let dir = scratch();
    let out = run_in(
        dir.path(),
        &["man", "--dir", dir.path().to_str().expect("utf-8")],
    );
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    for name in named.iter().chain([&"plc-conformance.1".to_string()]) {
        assert!(dir.path().join(name).is_file(), "{name} was not written");
    }
}
