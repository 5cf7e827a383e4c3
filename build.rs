//! Embeds the shipped vendor profiles (`vendors/`) and corpus (`vectors/`) in the binary, so that
//! an installed `plc-conformance` runs them from any folder (see `load::source`).

use std::path::{Path, PathBuf};

fn yaml_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            yaml_files(&path, out);
        } else if matches!(
            path.extension().and_then(|e| e.to_str()),
            Some("yaml" | "yml")
        ) {
            out.push(path);
        }
    }
}

fn main() {
    let manifest = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets it"));
    let mut files = Vec::new();
    for folder in ["vendors", "vectors"] {
        // A folder (any file below it) that changes rebuilds the embedded copy.
        println!("cargo:rerun-if-changed={folder}");
        yaml_files(&manifest.join(folder), &mut files);
    }
    files.sort();
    let mut code = String::from(
        "/// Every embedded file: its path relative to the project root, `/`-separated, and its \
         text.\npub(crate) static FILES: &[(&str, &str)] = &[\n",
    );
    for file in &files {
        let relative = file
            .strip_prefix(&manifest)
            .expect("below the manifest")
            .components()
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect::<Vec<_>>()
            .join("/");
        code.push_str(&format!(
            "    ({relative:?}, include_str!({:?})),\n",
            file.display().to_string()
        ));
    }
    code.push_str("];\n");
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets it"));
    std::fs::write(out.join("embedded.rs"), code).expect("write embedded.rs");
}
