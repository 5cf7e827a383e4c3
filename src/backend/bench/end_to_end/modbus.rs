//! Cross-checks of the Modbus TCP link against independent code, so that a misreading of the
//! frames shared by this harness's client and its simulated IDEC CPU cannot pass unseen: the
//! client and the IDEC link against pymodbus's server (reads and writes at the limits, an
//! exception as a protocol fault), and pymodbus's client against the simulated CPU. pymodbus is
//! pinned in adapters/python/requirements.txt; the tests are skipped with a note when
//! `.venv-adapters` lacks it, and fail then when PLC_CONFORMANCE_REQUIRE_BACKENDS is set. All
//! traffic stays on 127.0.0.1.

#[cfg(test)]
use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};

use crate::backend::bench::fence::{WordRange, WriteFence};
use crate::backend::bench::mailbox;
use crate::backend::bench::manifest::Manifest;
use crate::backend::bench::tcp::TransportError;
use crate::backend::bench::{Failure, LinkError, LinkSettings};
use crate::backend::modbus::client::{ModbusClient, ModbusError, ModbusSettings};
use crate::backend::modbus::sim::{ModbusSimSettings, ModbusSimulator};
use crate::backend::modbus::{Map, ModbusLinkSettings};
use crate::hil::{generate, GenerateOptions};
use crate::Device;

use super::{reference, root, session, succeeded};

/// The Python of `.venv-adapters` with pymodbus, or `None` (with a note).
fn venv_python() -> Option<PathBuf> {
    super::adapters_python("pymodbus", "pymodbus")
}

/// pymodbus's Modbus TCP server on 127.0.0.1; it ends when its stdin closes (on drop).
struct Pymodbus {
    child: Child,
    address: String,
}

impl Pymodbus {
    fn start(python: &PathBuf, args: &[&str]) -> Pymodbus {
        let mut child = Command::new(python)
            .arg(root().join("tests/fixtures/modbus/pymodbus_server.py"))
            .arg("0")
            .args(args)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("pymodbus starts");
        let stdout = child.stdout.take().expect("stdout");
        let line = BufReader::new(stdout)
            .lines()
            .next()
            .expect("the server printed its address")
            .expect("a line");
        let address = line
            .strip_prefix("listening on ")
            .unwrap_or_else(|| panic!("not an address: {line}"))
            .to_string();
        Pymodbus { child, address }
    }
}

/// pymodbus's server with the registers of `init` (its JSON) and `args`, and the scratch folder
/// that holds `init` (keep it as long as the server); `None` (with a note) without pymodbus.
fn pymodbus_with(init: &str, args: &[&str]) -> Option<(tempfile::TempDir, Pymodbus)> {
    let python = venv_python()?;
    let dir = super::scratch();
    let file = dir.path().join("init.json");
    std::fs::write(&file, init).expect("write");
    let mut all = vec!["--init", file.to_str().expect("utf-8")];
    all.extend_from_slice(args);
    let server = Pymodbus::start(&python, &all);
    Some((dir, server))
}

impl Drop for Pymodbus {
    fn drop(&mut self) {
        drop(self.child.stdin.take());
        let _ = self.child.wait();
    }
}

/// The client reads and writes pymodbus's registers at the specification's limits (125 read,
/// 123 written in one request), splits what is longer, writes one word with function 06, reads
/// coils, and an exception is a protocol fault that keeps the connection.
#[test]
fn the_client_reads_and_writes_pymodbus_at_the_limits() {
    let Some((_dir, server)) = pymodbus_with(
        r#"{"holding": {"100": 4660, "8002": 6}}"#,
        &["--coils-on", "9000,9004", "--holding", "10000"],
    ) else {
        return;
    };
    let mut c = ModbusClient::new(ModbusSettings::new(server.address.clone()));
    assert_eq!(c.read_holding(100, 1).expect("read"), [4660]);
    let words: Vec<u16> = (0..300u16).map(|i| i.wrapping_mul(257) ^ 0x5A00).collect();
    let before = c.requests();
    c.write_registers(0, &words[..123]).expect("123 words");
    assert_eq!(c.requests() - before, 1, "123 words are one request");
    let read = c.read_holding(0, 125).expect("125 words");
    assert_eq!(c.requests() - before, 2, "125 words are one request");
    assert_eq!(&read[..123], &words[..123]);
    assert_eq!(&read[123..], [0, 0]);
    let before = c.requests();
    c.write_registers(1000, &words).expect("300 words");
    assert_eq!(c.requests() - before, 3, "123 + 123 + 54");
    assert_eq!(c.read_holding(1000, 300).expect("300 words"), words);
    assert_eq!(c.requests() - before, 6, "125 + 125 + 50");
    c.write_registers(200, &[0xBEEF]).expect("one word");
    assert_eq!(c.read_holding(199, 3).expect("read"), [0, 0xBEEF, 0]);
    assert_eq!(
        c.read_coils(9000, 5).expect("coils"),
        [true, false, false, false, true]
    );
    let connections = c.connections();
    let e = c
        .read_holding(9995, 10)
        .expect_err("past the server's registers");
    assert!(matches!(e, ModbusError::Exception { code: 2, .. }), "{e}");
    assert!(e.to_string().contains("ILLEGAL DATA ADDRESS"), "{e}");
    let fault = LinkError::from(e).fault();
    assert_eq!(fault.kind(), "protocol-error");
    assert_eq!(c.read_holding(8002, 1).expect("read"), [6]);
    assert_eq!(
        c.connections(),
        connections,
        "an exception keeps the connection"
    );
    // A request past the last address is refused before anything is sent.
    let sent = c.requests();
    let e = c.read_holding(65530, 10).expect_err("past 0xFFFF");
    assert!(
        matches!(e, ModbusError::Transport(TransportError::Request { .. })),
        "{e}"
    );
    assert_eq!(c.requests(), sent);
}

/// The IDEC link over pymodbus's server: the type code from D8002, RUN from M8000 (coil 9000),
/// and a fenced write landing where the map puts D words.
#[test]
fn the_idec_link_names_the_cpu_and_writes_through_the_fence_on_pymodbus() {
    let Some((_dir, server)) =
        pymodbus_with(r#"{"holding": {"8002": 6}}"#, &["--coils-on", "9000"])
    else {
        return;
    };
    let project = session();
    let map = Map::of(project.profiles.get("idec-fc4a").expect("profile")).expect("map");
    let settings = ModbusLinkSettings {
        client: ModbusSettings::new(server.address.clone()),
        map: std::sync::Arc::new(map),
    };
    let mut link = settings.open();
    let identity = link.identify().expect("identify");
    assert_eq!(identity.name, "6");
    let state = link.run_state().expect("state");
    assert!(state.running, "{}", state.text);
    let fence = WriteFence::new(vec![WordRange::new("D", 500, 799)]);
    let words: Vec<u16> = (0..200).collect();
    for w in fence
        .writes(link.batch_words(), &Device::new("D", 550), &words)
        .expect("inside")
    {
        link.write(&w).expect("written");
    }
    assert_eq!(link.read(&Device::new("D", 550), 200).expect("read"), words);
    let mut c = ModbusClient::new(settings.client.clone());
    assert_eq!(c.read_holding(550, 3).expect("read"), [0, 1, 2]);
    let e = link
        .read(&Device::new("D", 9000), 1)
        .expect_err("not in the map");
    assert_eq!(e.failure, Failure::Protocol);
    assert!(e.to_string().contains("not a holding register"), "{e}");
}

fn idec_manifest() -> Manifest {
    generate(
        &session(),
        &GenerateOptions {
            profile: "idec-fc4a".into(),
            variants: vec!["d40k3".into()],
            ..GenerateOptions::default()
        },
    )
    .expect("generate")
    .manifest
}

/// pymodbus's client against the simulated IDEC CPU: it reads the type code, the start control
/// relay and the program's signature, writes and reads back a word of the manifest's windows,
/// and gets exception 02 past the map.
#[test]
fn pymodbus_reads_and_writes_the_simulated_idec_cpu() {
    let Some(python) = venv_python() else {
        return;
    };
    let project = session();
    let m = idec_manifest();
    let profile = project.profiles.get(&m.profile).cloned().expect("profile");
    let sim = ModbusSimulator::start(
        ModbusSimSettings::idec(m.clone(), "d40k3", 6),
        profile,
        reference(&project, "idec-fc4a"),
    )
    .expect("simulator");
    let head = Device::new("D", m.mailbox.trim_start_matches('D').parse().expect("D"));
    let window = m.writes.first().expect("a window").clone();
    let word: u32 = window
        .trim_start_matches('D')
        .split('-')
        .next()
        .and_then(|n| n.parse().ok())
        .expect("a D range");
    let ops = [
        "r:8002:1".to_string(),
        "c:9000:1".to_string(),
        format!("r:{}:2", head.index),
        format!("w:{word}:4660,22136"),
        format!("r:{word}:2"),
        "r:8499:2".to_string(),
    ];
    let out = Command::new(&python)
        .arg(root().join("tests/fixtures/modbus/pymodbus_client.py"))
        .arg(sim.address().to_string())
        .args(&ops)
        .output()
        .expect("pymodbus client runs");
    let stdout = succeeded(&out, "");
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(
        lines,
        [
            "r 8002 6".to_string(),
            "c 9000 1".to_string(),
            format!(
                "r {} {} {}",
                head.index,
                mailbox::MAGIC[0],
                mailbox::MAGIC[1]
            ),
            format!("w {word} ok"),
            format!("r {word} 4660 22136"),
            "x 3 2".to_string(),
        ]
    );
    assert_eq!(sim.read(&Device::new("D", word)), 4660);
    let audit = sim.audit();
    assert!(audit.stray_writes.is_empty(), "{:?}", audit.stray_writes);
}
