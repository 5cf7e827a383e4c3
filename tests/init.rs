//! `plc-conformance init codec`: the scaffold a library maintainer starts from runs as written
//! (the Python one green, its stand-in reading as the manuals do; with a lenient conversion in
//! its place, the differences such a conversion has fail), and nothing is replaced.

mod common;

use std::path::Path;

use common::{bin, root, scratch};

/// A process's exit status and what it said, its output then its errors.
fn said(out: &std::process::Output) -> (Option<i32>, String) {
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    (out.status.code(), text)
}

/// `init codec` with `args` in `dir`: the exit status and what it said.
fn init(dir: &Path, args: &[&str]) -> (Option<i32>, String) {
    let out = bin()
        .current_dir(dir)
        .args(["init", "codec"])
        .args(args)
        .output()
        .expect("runs");
    said(&out)
}

/// Runs the scaffold's own command (`command` starts its adapter) in `dir`.
fn run_adapter(dir: &Path, command: &str, env: &[(&str, &Path)]) -> (Option<i32>, String) {
    let mut run = bin();
    run.current_dir(dir).args([
        "run",
        "--backend",
        &format!("external:mylib={command}"),
        "--known-differences",
        "mylib=mylib.known.yaml",
    ]);
    for (k, v) in env {
        run.env(k, v);
    }
    let out = run.output().expect("runs");
    said(&out)
}

/// Runs the Python scaffold's pytest file in `dir` with the Python of `.venv-adapters` (pytest
/// pinned there), the package from `python/` and this build's command first on PATH.
fn pytest(python: &Path, dir: &Path, file: &str) -> (Option<i32>, String) {
    let command = Path::new(env!("CARGO_BIN_EXE_plc-conformance"));
    let path = std::env::join_paths(
        std::iter::once(command.parent().expect("a folder").to_path_buf()).chain(
            std::env::split_paths(&std::env::var_os("PATH").unwrap_or_default()),
        ),
    )
    .expect("PATH");
    let package = std::env::join_paths([root().join("python"), root().join("adapters/python")])
        .expect("PYTHONPATH");
    let out = std::process::Command::new(python)
        .current_dir(dir)
        .args(["-m", "pytest", "-q", "-p", "no:cacheprovider", file])
        .env("PATH", path)
        .env("PYTHONPATH", package)
        .output()
        .expect("pytest runs");
    said(&out)
}

/// The scaffold's stand-in replaced by Python's int(text, 16), a common choice.
fn with_int_stand_in(dir: &Path, file: &str) {
    let path = dir.join(file);
    let text = std::fs::read_to_string(&path).expect("the test file");
    let at = text
        .find("    return int(field, 16)")
        .expect("the stand-in");
    let start = text[..at].rfind("def decode").expect("decode");
    let body = text[start..].find("\n\n\n").expect("decode's end") + start;
    let lenient =
        "def decode(text, digits):\n    return int(text[:digits].decode(\"latin-1\"), 16)";
    std::fs::write(
        &path,
        format!("{}{}{}", &text[..start], lenient, &text[body..]),
    )
    .expect("write");
}

#[test]
fn a_python_scaffold_runs_green_as_written_and_is_never_replaced() {
    let dir = scratch();
    let (code, said) = init(dir.path(), &["--python", "--name", "mylib"]);
    assert_eq!(code, Some(0), "{said}");
    let test_file = "test_mylib_conformance.py";
    for file in [
        test_file,
        "mylib.known.yaml",
        ".github/workflows/plc-conformance.yml",
    ] {
        let text = std::fs::read_to_string(dir.path().join(file)).expect(file);
        assert!(!text.contains("{{"), "{file} keeps a placeholder:\n{text}");
    }
    assert!(
        said.contains("pytest -q test_mylib_conformance.py"),
        "{said}"
    );
    let ci = std::fs::read_to_string(dir.path().join(".github/workflows/plc-conformance.yml"))
        .expect("ci");
    let pinned = format!(
        "pip install \"plc-conformance[pytest]=={}\"",
        env!("CARGO_PKG_VERSION")
    );
    assert!(ci.contains(&pinned), "{ci}");
    assert!(ci.contains("pytest -q test_mylib_conformance.py"), "{ci}");
    // Run again: nothing is replaced.
    std::fs::write(dir.path().join("mylib.known.yaml"), "edited").expect("write");
    let (code, said) = init(dir.path(), &["--python", "--name", "mylib"]);
    assert_eq!(code, Some(2), "{said}");
    assert!(said.contains("init writes only where no file is"), "{said}");
    let kept = std::fs::read_to_string(dir.path().join("mylib.known.yaml")).expect("kept");
    assert_eq!(kept, "edited");
    std::fs::remove_file(dir.path().join("mylib.known.yaml")).expect("rm");
    std::fs::remove_dir_all(dir.path().join(".github")).expect("rm");
    std::fs::remove_file(dir.path().join(test_file)).expect("rm");
    init(dir.path(), &["--python", "--name", "mylib"]);
    let Some(python) = common::adapters_python("pytest", "pytest") else {
        return;
    };
    // As written: green, every case conforming or skipped with its reason.
    let (code, said) = pytest(&python, dir.path(), test_file);
    assert_eq!(code, Some(0), "{said}");
    assert!(said.contains(" passed"), "{said}");
    // With Python's int(text, 16) in the stand-in's place, the differences such a conversion
    // has fail their tests: lowercase digits, signs, 0x.
    with_int_stand_in(dir.path(), test_file);
    let (code, said) = pytest(&python, dir.path(), test_file);
    assert_eq!(code, Some(1), "{said}");
    assert!(said.contains("xv-h2v-61h"), "{said}");
    assert!(said.contains(" failed"), "{said}");
}

#[test]
fn a_javascript_scaffold_runs_as_written() {
    let node = std::process::Command::new("node").arg("--version").output();
    if node.is_err() {
        assert!(
            std::env::var_os("PLC_CONFORMANCE_REQUIRE_BACKENDS").is_none(),
            "node is required"
        );
        eprintln!("skipped: node is not installed");
        return;
    }
    let dir = scratch();
    let (code, said) = init(dir.path(), &["--js", "--name", "mylib"]);
    assert_eq!(code, Some(0), "{said}");
    // The helper, where `npm install PATH/TO/adapters/js` puts it.
    let modules = dir.path().join("node_modules");
    std::fs::create_dir(&modules).expect("mkdir");
    std::os::unix::fs::symlink(
        root().join("adapters/js"),
        modules.join("plc-conformance-adapter"),
    )
    .expect("link");
    // As written: green, its stand-in reading as the manuals do.
    let (code, said) = run_adapter(dir.path(), "node mylib_adapter.js", &[]);
    assert_eq!(code, Some(0), "{said}");
    // With parseInt in the stand-in's place (it stops at the first character it cannot read,
    // and takes lowercase), the differences such a conversion has.
    let adapter = dir.path().join("mylib_adapter.js");
    let text = std::fs::read_to_string(&adapter).expect("adapter");
    let start = text.find("  decode(text, digits) {").expect("decode");
    let end = text[start..].find("\n  },\n").expect("decode's end") + start + "\n  },\n".len();
    let lenient = "  decode(text, digits) {\n    const value = parseInt(text.subarray(0, digits).toString('latin1'), 16);\n    if (Number.isNaN(value)) throw new CodecError('invalid-digit');\n    return value;\n  },\n";
    std::fs::write(
        &adapter,
        format!("{}{}{}", &text[..start], lenient, &text[end..]),
    )
    .expect("write");
    let (code, said) = run_adapter(dir.path(), "node mylib_adapter.js", &[]);
    assert_eq!(code, Some(1), "{said}");
    assert!(
        said.contains("cross-vendor::mylib::codec::xv-h2v-61h"),
        "{said}"
    );
}

#[test]
fn a_rust_scaffold_names_its_codec_after_the_backend() {
    let dir = scratch();
    let (code, said) = init(dir.path(), &["--rust", "--name", "my-lib"]);
    assert_eq!(code, Some(0), "{said}");
    let test = std::fs::read_to_string(dir.path().join("tests/conformance.rs")).expect("written");
    assert!(test.contains("struct MyLibCodec;"), "{test}");
    assert!(
        test.contains("Some(\"my-lib.known.yaml\".into())"),
        "{test}"
    );
    assert!(!test.contains("{{"), "{test}");
    // The corpus the crate carries, not a checkout beside it.
    assert!(test.contains("Harness::embedded()"), "{test}");
    let (code, said) = init(dir.path(), &["--rust", "--name", "My Lib"]);
    assert_eq!(code, Some(2), "{said}");
    assert!(
        said.contains("--name My Lib: use lowercase letters"),
        "{said}"
    );
}

/// `--protocol` writes the protocol into the scaffold, and the first run judges the stand-in by
/// that protocol's manual: int(text, 16) breaks Modbus ASCII's character rule, and the
/// difference names it. A protocol no profile defines is refused with the list.
#[test]
fn a_scaffold_for_a_protocol_is_judged_by_it() {
    let dir = scratch();
    let (code, said) = init(
        dir.path(),
        &["--python", "--name", "mylib", "--protocol", "modbus-ascii"],
    );
    assert_eq!(code, Some(0), "{said}");
    let test_file = "test_mylib_conformance.py";
    let written = std::fs::read_to_string(dir.path().join(test_file)).expect("test file");
    assert!(
        written.contains("    protocol=\"modbus-ascii\","),
        "{written}"
    );
    let other = scratch();
    let (code, said) = init(other.path(), &["--js", "--protocol", "modbus"]);
    assert_eq!(code, Some(2), "{said}");
    assert!(said.contains("the protocols are: "), "{said}");
    assert!(said.contains("modbus-ascii"), "{said}");
    assert!(!other.path().join("mylib_adapter.js").exists());
    let Some(python) = common::adapters_python("pytest", "pytest") else {
        return;
    };
    // As written: green against the protocol's corpus (a field is exactly its digits).
    let (code, said) = pytest(&python, dir.path(), test_file);
    assert_eq!(code, Some(0), "{said}");
    // int(text, 16) takes lowercase: the protocol's rule says why that fails, with its page.
    with_int_stand_in(dir.path(), test_file);
    let (code, said) = pytest(&python, dir.path(), test_file);
    assert_eq!(code, Some(1), "{said}");
    assert!(
        said.contains("rule:        modbus-ascii/B3 (mbsl p.17"),
        "{said}"
    );
    assert!(!said.contains("cross-vendor::mylib"), "{said}");
}

/// A scaffold is written whole or not at all: a `.github` that is a file, or a link out of the
/// folder, is refused before any file is written.
#[test]
fn a_scaffold_is_written_whole_or_not_at_all() {
    let dir = scratch();
    std::fs::write(dir.path().join(".github"), "a file").expect("write");
    let (code, said) = init(dir.path(), &["--python", "--name", "mylib"]);
    assert_eq!(code, Some(2), "{said}");
    assert!(
        said.contains(".github is a file where init needs a folder"),
        "{said}"
    );
    assert!(
        !dir.path().join("test_mylib_conformance.py").exists(),
        "{said}"
    );
    assert!(!dir.path().join("mylib.known.yaml").exists(), "{said}");
    #[cfg(unix)]
    {
        let other = scratch();
        let outside = scratch();
        std::os::unix::fs::symlink(outside.path(), other.path().join(".github")).expect("link");
        let (code, said) = init(other.path(), &["--python", "--name", "mylib"]);
        assert_eq!(code, Some(2), "{said}");
        assert!(said.contains("is a link"), "{said}");
        assert!(
            !other.path().join("test_mylib_conformance.py").exists(),
            "{said}"
        );
        assert!(
            std::fs::read_dir(outside.path())
                .expect("dir")
                .next()
                .is_none(),
            "nothing written through the link"
        );
    }
}
