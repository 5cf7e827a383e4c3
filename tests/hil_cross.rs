//! Cross-checks of the SLMP codec against independent implementations, so that a misreading of
//! the frame layout shared by this harness's client and its simulated CPU cannot pass unseen:
//! the client against virtual-plc (a Python SLMP server), and pymcprotocol (a Python SLMP
//! client) against the simulated CPU. Both are pinned in adapters/python/requirements.txt; the
//! tests are skipped with a note when `.venv-adapters` is missing, and fail then when
//! PLC_CONFORMANCE_REQUIRE_BACKENDS is set. All traffic stays on 127.0.0.1.

mod common;

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::Duration;

use plc_conformance::backend::slmp::client::{Client, ClientError, ClientSettings, Code};
use plc_conformance::backend::slmp::fault_of;
use plc_conformance::backend::slmp::fence::{WordRange, WriteFence};
use plc_conformance::backend::slmp::frame::{DeviceForm, FrameKind};
use plc_conformance::backend::slmp::sim::{SimSettings, Simulator};
use plc_conformance::device::Device;
use plc_conformance::hil::{generate, GenerateOptions};

use common::{reference, root, session};

/// The Python of `.venv-adapters`, or `None` (with a note) when it is not installed.
fn venv_python() -> Option<PathBuf> {
    let python = root().join(".venv-adapters/bin/python");
    let ok = python.exists()
        && Command::new(&python)
            .args(["-c", "import virtual_plc, pymcprotocol"])
            .output()
            .is_ok_and(|o| o.status.success());
    assert!(
        ok || std::env::var_os("PLC_CONFORMANCE_REQUIRE_BACKENDS").is_none(),
        "virtual-plc and pymcprotocol are required (.venv-adapters)"
    );
    if !ok {
        eprintln!(
            "skipped: virtual-plc and pymcprotocol are not installed; install them with \
             `python3 -m venv .venv-adapters && .venv-adapters/bin/pip install -r \
             adapters/python/requirements.txt`"
        );
    }
    ok.then_some(python)
}

/// A virtual-plc server on 127.0.0.1, killed when dropped.
struct VirtualPlc {
    child: Child,
    address: String,
}

impl VirtualPlc {
    fn start(python: &PathBuf, profile: &str, extra: &[&str]) -> VirtualPlc {
        let mut child = Command::new(python)
            .args(["-m", "virtual_plc", "--host", "127.0.0.1", "--port", "0"])
            .args(["--profile", profile, "--text-pad", "32"])
            .args(extra)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("virtual-plc starts");
        let stderr = child.stderr.take().expect("stderr");
        let mut lines = BufReader::new(stderr).lines();
        let address = loop {
            let line = lines
                .next()
                .expect("virtual-plc printed its banner")
                .expect("a line");
            if let Some(rest) = line.strip_prefix("listening on ") {
                break rest
                    .split_whitespace()
                    .next()
                    .expect("HOST:PORT")
                    .to_string();
            }
        };
        // Keep reading its stderr so that it never blocks on a full pipe.
        std::thread::spawn(move || for _ in lines {});
        VirtualPlc { child, address }
    }
}

impl Drop for VirtualPlc {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn client(address: &str, frame: FrameKind, form: DeviceForm) -> Client {
    let mut s = ClientSettings::new(address);
    s.frame = frame;
    s.form = form;
    s.reply_timeout = Duration::from_millis(600);
    s.read_retries = 0;
    Client::new(s)
}

/// The client's four commands against virtual-plc in both frames, both device forms and both
/// codes: what it writes reads back, from a batch and from a random read, and 0101 decodes.
#[test]
fn the_client_talks_to_virtual_plc() {
    let Some(python) = venv_python() else { return };
    for (profile, frame, form, code) in [
        ("iQ-R", FrameKind::E4, DeviceForm::Long, Code::Binary),
        ("iQ-R", FrameKind::E3, DeviceForm::Long, Code::Binary),
        ("Q", FrameKind::E3, DeviceForm::Short, Code::Binary),
        ("Q", FrameKind::E4, DeviceForm::Short, Code::Binary),
        ("iQ-R", FrameKind::E4, DeviceForm::Long, Code::Ascii),
        ("iQ-R", FrameKind::E3, DeviceForm::Long, Code::Ascii),
        ("Q", FrameKind::E3, DeviceForm::Short, Code::Ascii),
        ("Q", FrameKind::E4, DeviceForm::Short, Code::Ascii),
    ] {
        let server = VirtualPlc::start(&python, profile, &[]);
        let mut c = client(&server.address, frame, form);
        c.settings_mut().code = code;
        let frame = format!("{frame} {code}");
        let name = c
            .type_name()
            .unwrap_or_else(|e| panic!("{profile} {frame}: {e}"));
        assert!(!name.name.is_empty(), "{profile} {frame}: {name}");
        let fence = WriteFence::new(vec![WordRange::new("D", 100, 199)]);
        let words = [0x0001, 0x8000, 0xFFFF, 0x5A8D];
        for w in fence
            .writes(form, &Device::new("D", 100), &words)
            .expect("inside")
        {
            c.write(&w)
                .unwrap_or_else(|e| panic!("{profile} {frame}: {e}"));
        }
        let back = c
            .read_words(&Device::new("D", 100), 4)
            .unwrap_or_else(|e| panic!("{profile} {frame}: {e}"));
        assert_eq!(back, words, "{profile} {frame}");
        let random = c
            .random_read(&[Device::new("D", 103), Device::new("D", 101)])
            .unwrap_or_else(|e| panic!("{profile} {frame}: {e}"));
        assert_eq!(random, [0x5A8D, 0x8000], "{profile} {frame}");
        let sd203 = c
            .random_read(&[Device::new("SD", 203)])
            .unwrap_or_else(|e| panic!("{profile} {frame}: {e}"));
        eprintln!(
            "virtual-plc {profile} {frame}: type name {name}, SD203 = {:04X}H in RUN",
            sd203[0]
        );
    }
}

/// virtual-plc's fault plan, on 1401 writes the client never repeats: an error end code keeps
/// the connection, a close is a crash, a late reply a timeout.
#[test]
fn virtual_plc_faults_map_to_their_kinds() {
    let Some(python) = venv_python() else { return };
    let dir = common::scratch();
    let plan = dir.path().join("faults.json");
    // virtual-plc counts `nth` per connection, and the first step that matches wins once: the
    // first two faults hit the first connection, the delay the first write of the second.
    std::fs::write(
        &plan,
        r#"{"steps": [
            {"match": {"command": 5121, "nth": 1}, "action": {"type": "bad_end_code", "code": 49238}},
            {"match": {"command": 5121, "nth": 2}, "action": {"type": "close_before_response"}},
            {"match": {"command": 5121, "nth": 1}, "action": {"type": "delay", "seconds": 1.5}}
        ]}"#,
    )
    .expect("plan");
    let server = VirtualPlc::start(
        &python,
        "iQ-R",
        &["--fault-plan", plan.to_str().expect("utf-8")],
    );
    let mut c = client(&server.address, FrameKind::E4, DeviceForm::Long);
    let fence = WriteFence::new(vec![WordRange::new("D", 0, 9)]);
    let write = || {
        fence
            .writes(DeviceForm::Long, &Device::new("D", 0), &[7])
            .expect("inside")
            .remove(0)
    };
    let e = c.write(&write()).expect_err("end code");
    assert!(
        matches!(e, ClientError::EndCode { code: 0xC056, .. }),
        "{e}"
    );
    assert_eq!(fault_of(&e).kind(), "protocol-error");
    assert!(c.is_connected(), "an error answer keeps the connection");
    let e = c.write(&write()).expect_err("closed");
    assert!(matches!(e, ClientError::Closed { .. }), "{e}");
    assert_eq!(fault_of(&e).kind(), "crashed");
    let e = c.write(&write()).expect_err("late");
    assert!(matches!(e, ClientError::Timeout { .. }), "{e}");
    assert_eq!(fault_of(&e).kind(), "timeout");
    // And the next request, on a new connection, is answered.
    c.write(&write()).expect("a fourth write");
    assert_eq!(c.read_words(&Device::new("D", 0), 1).expect("read"), [7]);
}

/// pymcprotocol, an independent client, against the simulated CPU: it reads the program's
/// signature, writes and reads back a window word, random-reads and reads the type name, in the
/// long device form (plctype iQ-R) and the Q-compatible one (plctype Q).
#[test]
fn pymcprotocol_talks_to_the_simulated_cpu() {
    let Some(python) = venv_python() else { return };
    let project = session();
    let manifest = generate(
        &project,
        &GenerateOptions {
            profile: "mitsubishi-iqr".into(),
            variants: vec!["rcpu".into()],
            ..GenerateOptions::default()
        },
    )
    .expect("generate")
    .manifest;
    let head = manifest.mailbox_head().expect("mailbox");
    let profile = project
        .profiles
        .get("mitsubishi-iqr")
        .cloned()
        .expect("profile");
    for (plctype, long_form) in [("iQ-R", true), ("Q", false)] {
        let mut s = SimSettings::new(manifest.clone(), "rcpu", "R04CPU");
        s.long_form = long_form;
        let sim = Simulator::start(s, profile.clone(), reference(&project, "mitsubishi-iqr"))
            .expect("simulator");
        let script = format!(
            "import sys\n\
             from pymcprotocol import Type3E\n\
             c = Type3E(plctype='{plctype}')\n\
             c.connect('127.0.0.1', {port})\n\
             print(c.batchread_wordunits('{head}', 6))\n\
             c.batchwrite_wordunits('D100', [1, -2, 300])\n\
             print(c.batchread_wordunits('D100', 3))\n\
             print(c.randomread(['D102', '{layout}'], [])[0])\n\
             print(c.read_cputype()[0].strip())\n",
            port = sim.address().port(),
            layout = Device::new(head.code(), head.index + 2),
        );
        let out = Command::new(&python)
            .args(["-c", &script])
            .output()
            .expect("python runs");
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{plctype}: {stdout}{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let hash = manifest.hash32();
        let signed = |w: u32| i32::from(w as u16 as i16);
        let expected = format!(
            "[17232, 18760, 1, {}, {}, {}]\n[1, -2, 300]\n[300, 1]\nR04CPU\n",
            signed(hash & 0xFFFF),
            signed(hash >> 16),
            manifest.rungs.len()
        );
        assert_eq!(stdout, expected, "{plctype}");
        assert_eq!(sim.read(&Device::new("D", 101)), 0xFFFE, "{plctype}");
        assert!(sim.audit().stray_writes.is_empty(), "{plctype}");
    }
}
