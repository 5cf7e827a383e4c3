//! One version for everything the project ships: the crate (and the command), the wheel built
//! from it (its `pyproject.toml` takes the crate's version), the npm package (the JavaScript
//! helper, packed with the command) and the Python helper package. A release bumps
//! `Cargo.toml` and these follow it, or this test names the one left behind.

use std::path::Path;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn read(relative: &str) -> String {
    std::fs::read_to_string(root().join(relative)).unwrap_or_else(|e| panic!("{relative}: {e}"))
}

/// The value of the first line of `text` that starts with `key` (`version = "0.1.0"`,
/// `"version": "0.1.0",`, `__version__ = "0.1.0"`), without its quotes.
fn value_of(text: &str, key: &str) -> Option<String> {
    let line = text.lines().find(|l| l.trim_start().starts_with(key))?;
    let (_, value) = line.split_once(['=', ':'])?;
    Some(
        value
            .trim()
            .trim_end_matches(',')
            .trim_matches('"')
            .to_string(),
    )
}

#[test]
fn the_crate_the_wheel_and_the_packages_have_one_version() {
    let crate_version = env!("CARGO_PKG_VERSION");
    let wheel = read("pyproject.toml");
    assert!(
        wheel.contains("dynamic = [\"version\"]"),
        "the wheel takes its version from Cargo.toml"
    );
    for (file, key) in [
        ("adapters/js/package.json", "\"version\""),
        ("adapters/python/pyproject.toml", "version"),
        ("adapters/python/plc_adapter.py", "__version__"),
    ] {
        assert_eq!(
            value_of(&read(file), key).as_deref(),
            Some(crate_version),
            "{file}: its version is not the crate's {crate_version}"
        );
    }
    assert!(
        read("adapters/js/index.js").contains("require('./package.json').version"),
        "the JavaScript helper reads its version from its package"
    );
}
