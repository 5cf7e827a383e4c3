//! `init codec`: the files a library maintainer starts from — a commented pytest file (Python),
//! adapter (JavaScript) or test (Rust) that runs as it is (a stand-in conversion that reads as
//! the manuals do stands where the library's calls go), an empty known-differences file and a
//! CI job (`docs/check-your-library.md` walks from them).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::{output, CliError, Outcome, EXIT_OK};
use crate::load::valid_name;

#[derive(Debug, clap::Subcommand)]
pub(crate) enum InitCommand {
    /// A codec-level backend for a library's hex conversions: its adapter, its
    /// known-differences file and a CI job.
    Codec(CodecArgs),
}

#[derive(Debug, clap::Args)]
#[command(group(clap::ArgGroup::new("language").required(true).args(["python", "js", "rust"])))]
pub(crate) struct CodecArgs {
    /// A pytest file, through the plc-conformance wheel's pytest entry (codec_cases).
    #[arg(long)]
    pub python: bool,
    /// An adapter in JavaScript, through the plc-conformance-adapter helper.
    #[arg(long)]
    pub js: bool,
    /// A `harness = false` test of a Rust crate, through plc_conformance::Codec.
    #[arg(long)]
    pub rust: bool,
    /// The backend's name, in trial names and file names (lowercase letters, digits, `-`, `_`).
    #[arg(long, default_value = "mylib")]
    pub name: String,
    /// The folder to write into (your library's repository).
    #[arg(long, value_name = "DIR", default_value = ".")]
    pub dir: PathBuf,
    /// The communication protocol your library speaks (`mc-ascii`, `modbus-ascii`,
    /// `fx-computer-link`, `mewtocol-com`, `omron-host-link`, `keyence-kv-l2`): its own manual
    /// then judges the codec. Without it the scaffold names none, and the instruction manuals
    /// judge it.
    #[arg(long, value_name = "ID")]
    pub protocol: Option<String>,
}

/// One file of a scaffold: where it goes under the folder, and its template.
struct Template {
    path: String,
    text: &'static str,
}

const PYTHON: &str = include_str!("../../templates/init/test_codec.py");
const JS: &str = include_str!("../../templates/init/codec.js");
const RUST: &str = include_str!("../../templates/init/conformance.rs");
const KNOWN: &str = include_str!("../../templates/init/known.yaml");
const CI_PYTHON: &str = include_str!("../../templates/init/ci-python.yml");
const CI_JS: &str = include_str!("../../templates/init/ci-js.yml");
const CI_RUST: &str = include_str!("../../templates/init/ci-rust.yml");

pub(super) fn init(command: &InitCommand) -> Outcome {
    let InitCommand::Codec(args) = command;
    let name = &args.name;
    check_arguments(args)?;
    let (files, run) = scaffold(args);
    // Nothing is written when anything would be replaced: a scaffold is a start, not an edit.
    let taken: Vec<String> = (files.iter())
        .map(|f| args.dir.join(&f.path))
        .filter(|p| p.exists())
        .map(|p| p.display().to_string())
        .collect();
    if !taken.is_empty() {
        return Err(CliError::input(format!(
            "init writes only where no file is, and these exist: {}; give another --dir or \
             --name",
            taken.join(", ")
        )));
    }
    // All or none: every folder is checked and made before any file, and the files are staged
    // together and renamed into place together.
    for f in &files {
        refuse_linked_folders(&args.dir, &f.path)?;
    }
    let texts: Vec<(std::path::PathBuf, String)> = (files.iter())
        .map(|f| {
            let path = args.dir.join(&f.path);
            (path, fill(f.text, name, args.protocol.as_deref()))
        })
        .collect();
    for (path, _) in &texts {
        create_parent(path)?;
    }
    output::write_every(texts.iter().map(|(p, t)| (p.as_path(), t.as_str())))?;
    let mut said = String::new();
    for (path, _) in &texts {
        let _ = writeln!(said, "wrote {}", path.display());
    }
    let _ = write!(
        said,
        "next: put your library's calls where the stand-in is, then\n  {run}\n\
         the guide: docs/check-your-library.md"
    );
    output::write(None, &said)?;
    Ok(EXIT_OK)
}

/// The name a backend can have, and a protocol a profile defines.
fn check_arguments(args: &CodecArgs) -> Result<(), CliError> {
    let name = &args.name;
    if !valid_name(name) {
        return Err(CliError::input(format!(
            "--name {name}: use lowercase letters, digits, `-` and `_`"
        )));
    }
    if let Some(protocol) = &args.protocol {
        let known = crate::load::load_profiles(&crate::load::embedded_vendors())?
            .protocols
            .ids();
        if !known.contains(protocol) {
            return Err(CliError::input(format!(
                "--protocol {protocol}: no protocol profile has that id; the protocols are: {}",
                known.join(", ")
            )));
        }
    }
    Ok(())
}

/// The scaffold's files for the language asked (the adapter or test, the known-differences
/// file, the CI job) and the command that runs it.
fn scaffold(args: &CodecArgs) -> ([Template; 3], String) {
    let name = &args.name;
    // An adapter that a process runs: its file, and the command that runs it.
    let script = |extension: &str, interpreter: &str, text: &'static str| {
        let path = format!("{name}_adapter.{extension}");
        let run = format!(
            "plc-conformance run --backend 'external:{name}={interpreter} {path}' \
             --known-differences {name}={name}.known.yaml"
        );
        (Template { path, text }, run)
    };
    let ((adapter, run), ci) = if args.python {
        let path = format!("test_{}_conformance.py", python_name(name));
        let run = format!("pytest -q {path}");
        ((Template { path, text: PYTHON }, run), CI_PYTHON)
    } else if args.js {
        (script("js", "node", JS), CI_JS)
    } else {
        let test = Template {
            path: "tests/conformance.rs".into(),
            text: RUST,
        };
        let run = "cargo test --test conformance (after the Cargo.toml lines at the top of \
                   tests/conformance.rs)";
        ((test, run.to_string()), CI_RUST)
    };
    let files = [
        adapter,
        Template {
            path: format!("{name}.known.yaml"),
            text: KNOWN,
        },
        Template {
            path: ".github/workflows/plc-conformance.yml".into(),
            text: ci,
        },
    ];
    (files, run)
}

/// Refuses a folder on the way from `dir` to `relative`'s file that is a link (which would
/// take the file out of the folder given) or a file (where no file can go).
fn refuse_linked_folders(dir: &Path, relative: &str) -> Result<(), CliError> {
    let mut at = dir.to_path_buf();
    let folders: Vec<&str> = relative.split('/').collect();
    for part in &folders[..folders.len().saturating_sub(1)] {
        at.push(part);
        match std::fs::symlink_metadata(&at) {
            Ok(m) if m.file_type().is_symlink() => {
                return Err(CliError::input(format!(
                    "{} is a link: init writes into the folder given, not where a link leads",
                    at.display()
                )))
            }
            Ok(m) if !m.is_dir() => {
                return Err(CliError::input(format!(
                    "{} is a file where init needs a folder; nothing was written",
                    at.display()
                )))
            }
            _ => {}
        }
    }
    Ok(())
}

fn create_parent(path: &Path) -> Result<(), CliError> {
    match path.parent().filter(|p| !p.as_os_str().is_empty()) {
        Some(parent) => std::fs::create_dir_all(parent)
            .map_err(|e| CliError::input(format!("cannot create {}: {e}", parent.display()))),
        None => Ok(()),
    }
}

/// The backend's name as a Python identifier (`my-lib` is `my_lib`).
fn python_name(name: &str) -> String {
    name.replace('-', "_")
}

/// A template with the backend's name (`{{name}}`), its Python name (`{{ident}}`), its Rust type
/// (`{{type}}`: `my-lib` is `MyLibCodec`), the version of plc-conformance to install
/// (`{{version}}`), its protocol (`{{protocol_py}}`, `_js`, `_rs`: the line that names it, or the
/// same line commented out) and how the stand-ins take their field (`{{field_py}}`,
/// `{{field_js}}`, `{{field_rs}}`: a protocol's field is exactly its digits; an instruction reads the first
/// digits of a longer text) filled in.
fn fill(template: &str, name: &str, protocol: Option<&str>) -> String {
    let type_name: String = name
        .split(['-', '_'])
        .filter(|p| !p.is_empty())
        .map(|p| {
            let mut c = p.chars();
            c.next()
                .map(|f| f.to_ascii_uppercase().to_string() + c.as_str())
                .unwrap_or_default()
        })
        .collect();
    let type_name = match type_name.chars().next() {
        Some(c) if c.is_ascii_digit() => format!("Codec{type_name}"),
        _ => format!("{type_name}Codec"),
    };
    let (py, js, rs) = match protocol {
        Some(p) => (
            format!("protocol=\"{p}\","),
            format!("protocol: '{p}',"),
            format!(
                "protocol: Some(plc_conformance::ProtocolClaim {{ id: \"{p}\".into(), fields: None, \
                 cross_vendor: false }}),"
            ),
        ),
        None => (
            "# protocol=\"mc-ascii\",".to_string(),
            "// protocol: 'mc-ascii',".to_string(),
            "// protocol: Some(plc_conformance::ProtocolClaim { id: \"mc-ascii\".into(), fields: None, \
             cross_vendor: false }),"
                .to_string(),
        ),
    };
    // A protocol's field is exactly its digits; an instruction reads the first digits of a
    // longer text.
    let (field_py, field_js, field_rs) = match protocol {
        Some(_) => (
            "field = text\n    if len(field) != digits:\n        raise IndexError(\"a field of %d characters, not %d\" % (digits, len(field)))",
            "const field = text.toString('latin1');\n    if (field.length !== digits) throw new CodecError('invalid-count', `${field.length} characters`);",
            "let field = question.text;\n                if field.len() != question.digits as usize {\n                    return Ok(Answer::Error(ErrorClass::InvalidCount));\n                }",
        ),
        None => (
            "field = text[:digits]\n    if len(field) < digits:\n        raise ValueError(\"%d digits asked of %r\" % (digits, text))",
            "const field = text.subarray(0, digits).toString('latin1');\n    if (field.length < digits) throw new CodecError('invalid-digit', `${digits} digits asked`);",
            "let Some(field) = question.text.get(..question.digits as usize) else {\n                    return Ok(Answer::Error(ErrorClass::InvalidDigit));\n                };",
        ),
    };
    template
        .replace("{{name}}", name)
        .replace("{{ident}}", &python_name(name))
        .replace("{{version}}", env!("CARGO_PKG_VERSION"))
        .replace("{{field_py}}", field_py)
        .replace("{{field_js}}", field_js)
        .replace("{{field_rs}}", field_rs)
        .replace("{{type}}", &type_name)
        .replace("{{protocol_py}}", &py)
        .replace("{{protocol_js}}", &js)
        .replace("{{protocol_rs}}", &rs)
}

#[cfg(test)]
mod tests {
    use super::fill;

    #[test]
    fn a_template_gets_the_name_and_a_rust_type() {
        assert_eq!(
            fill("{{name}}: {{type}}", "my-lib_2", None),
            "my-lib_2: MyLib2Codec"
        );
        assert_eq!(fill("{{type}}", "9lives", None), "Codec9lives");
        assert_eq!(
            fill("{{protocol_py}} {{protocol_js}}", "x", Some("modbus-ascii")),
            "protocol=\"modbus-ascii\", protocol: 'modbus-ascii',"
        );
        assert!(fill("{{protocol_rs}}", "x", None).starts_with("// protocol:"));
    }
}
