//! Cross-checks of the SLMP codec against independent implementations, so that a misreading of
//! the frame layout shared by this harness's client and its simulated CPU cannot pass unseen:
//! the client against virtual-plc (a Python SLMP server), and pymcprotocol (a Python SLMP
//! client) against the simulated CPU, and a live run against aslmp's simulated CPUs (the
//! doctor first, on the bench a `--backend` text names). All are pinned in
//! adapters/python/requirements.txt; the tests are skipped with a note when `.venv-adapters` is
//! missing, and fail then when PLC_CONFORMANCE_REQUIRE_BACKENDS is set. All traffic stays on
//! 127.0.0.1.

#[cfg(test)]
use std::io::{BufRead, BufReader, Lines, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::Arc;
use std::time::Duration;

use crate::backend::bench::doctor::doctor;
use crate::backend::bench::fence::{self, WordRange, WriteFence};
use crate::backend::bench::manifest::Manifest;
use crate::backend::bench::tcp::TransportError;
use crate::backend::bench::BenchBackend;
use crate::backend::slmp::client::{Client, ClientError, ClientSettings, Code};
use crate::backend::slmp::frame::{DeviceForm, FrameKind};
use crate::backend::slmp::limits::{self, Family};
use crate::backend::slmp::sim::{RemoteProgram, SlmpSimSettings};
use crate::backend::slmp::{fault_of, SlmpBench, ADDRESSING};
use crate::hil::{generate, GenerateOptions};
use crate::{verdicts, Backend, Device, Trial};

use super::{reference, runnable, scratch, session, slmp_simulator, succeeded};

/// The Python of `.venv-adapters` with virtual-plc, pymcprotocol, aslmp and plc-comm-slmp, or `None` (with a note).
fn venv_python() -> Option<PathBuf> {
    super::adapters_python(
        "virtual_plc, pymcprotocol, aslmp, slmp",
        "virtual-plc, pymcprotocol, aslmp and plc-comm-slmp",
    )
}

/// A virtual-plc server on 127.0.0.1, killed when dropped.
struct VirtualPlc {
    child: Child,
    address: String,
}

impl VirtualPlc {
    fn start(python: &PathBuf, profile: &str, extra: &[&str]) -> VirtualPlc {
        let (child, mut lines) = spawn_reading(
            Command::new(python)
                .args(["-m", "virtual_plc", "--host", "127.0.0.1", "--port", "0"])
                .args(["--profile", profile, "--text-pad", "32"])
                .args(extra),
            true,
            "virtual-plc starts",
        );
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

/// Starts a Python tool (`what` in the message if it cannot start): its process, and the lines
/// of the stream it reports on, its stderr when `on_stderr` and else its stdout; the other
/// stream is discarded.
fn spawn_reading(
    command: &mut Command,
    on_stderr: bool,
    what: &str,
) -> (Child, Lines<BufReader<Box<dyn Read + Send>>>) {
    let (stdout, stderr) = if on_stderr {
        (Stdio::null(), Stdio::piped())
    } else {
        (Stdio::piped(), Stdio::null())
    };
    let mut child = command.stdout(stdout).stderr(stderr).spawn().expect(what);
    let stream: Box<dyn Read + Send> = if on_stderr {
        Box::new(child.stderr.take().expect("stderr"))
    } else {
        Box::new(child.stdout.take().expect("stdout"))
    };
    (child, BufReader::new(stream).lines())
}

impl Drop for VirtualPlc {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The manifest of the program generated for one variant of a profile.
fn generated(project: &crate::Project, profile: &str, variant: &str) -> Manifest {
    generate(
        project,
        &GenerateOptions {
            profile: profile.into(),
            variants: vec![variant.into()],
            ..GenerateOptions::default()
        },
    )
    .expect("generate")
    .manifest
}

/// The program generated for one variant of a profile, and the head of its mailbox.
fn generated_with_head(
    project: &crate::Project,
    profile: &str,
    variant: &str,
) -> (Manifest, Device) {
    let manifest = generated(project, profile, variant);
    let head = manifest.mailbox_head(&ADDRESSING).expect("mailbox");
    (manifest, head)
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
            .writes(960, &Device::new("D", 100), &words)
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
    let dir = super::scratch();
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
            .writes(960, &Device::new("D", 0), &[7])
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
    assert!(
        matches!(e, ClientError::Transport(TransportError::Closed { .. })),
        "{e}"
    );
    assert_eq!(fault_of(&e).kind(), "crashed");
    let e = c.write(&write()).expect_err("late");
    assert!(
        matches!(e, ClientError::Transport(TransportError::Timeout { .. })),
        "{e}"
    );
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
    let (manifest, head) = generated_with_head(&project, "mitsubishi-iqr", "rcpu");
    for (plctype, long_form) in [("iQ-R", true), ("Q", false)] {
        let sim = slmp_simulator(&project, &manifest, "rcpu", "R04CPU", |s| {
            s.link.long_form = long_form
        });
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
        let stdout = succeeded(&out, &format!("{plctype}: "));
        let hash = manifest.hash32();
        let signed = |w: u32| i32::from(w as u16 as i16);
        let expected = format!(
            "[17232, 18760, 2, {}, {}, {}]\n[1, -2, 300]\n[300, 2]\nR04CPU\n",
            signed(hash & 0xFFFF),
            signed(hash >> 16),
            manifest.rungs.len()
        );
        assert_eq!(stdout, expected, "{plctype}");
        assert_eq!(sim.read(&Device::new("D", 101)), 0xFFFE, "{plctype}");
        assert!(sim.audit().stray_writes.is_empty(), "{plctype}");
    }
}

/// aslmp's simulated CPU (`aslmp serve`) on 127.0.0.1, killed when dropped: its entries by name
/// (`tcp` 3E binary, `tcp-4e` 4E binary, `tcp-ascii` 3E ASCII code), as its banner lists them.
struct Aslmp {
    child: Child,
    entries: std::collections::BTreeMap<String, String>,
}

impl Aslmp {
    fn start(python: &PathBuf, target: &str) -> Aslmp {
        let (child, mut lines) = spawn_reading(
            Command::new(python)
                .args(["-m", "aslmp.tools", "serve", "--target", target])
                .args(["--host", "127.0.0.1"]),
            false,
            "aslmp serve starts",
        );
        let mut entries = std::collections::BTreeMap::new();
        for line in lines.by_ref() {
            let line = line.expect("a line");
            if line.starts_with("Ctrl-C") {
                break;
            }
            let mut words = line.split_whitespace();
            if let (Some(name), Some(address)) = (words.next(), words.next()) {
                if address.starts_with("127.0.0.1:") {
                    entries.insert(name.to_string(), address.to_string());
                }
            }
        }
        std::thread::spawn(move || for _ in lines {});
        assert!(entries.contains_key("tcp-ascii"), "{entries:?}");
        Aslmp { child, entries }
    }

    fn address(&self, entry: &str) -> &str {
        &self.entries[entry]
    }
}

impl Drop for Aslmp {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A client for a port of the family, with the limits of its code.
fn family_client(address: &str, family: Family, frame: FrameKind, code: Code) -> ClientSettings {
    let mut s = ClientSettings::new(address);
    s.frame = frame;
    s.code = code;
    s.form = match family {
        Family::Fx5 => DeviceForm::Short,
        Family::Iqr => DeviceForm::Long,
    };
    s.timer = limits::monitoring_timer(family);
    s.limits = limits::limits(family, code, s.form);
    s.reply_timeout = Duration::from_millis(1500);
    s
}

/// The client against aslmp's simulated FX5U-32MT/DS, in binary and ASCII code: 961 words
/// written and read back in batches the port takes (480 words in ASCII code), a random read
/// at the port's limit, and 0101; a batch of 481 words in ASCII code is refused with C052H,
/// which is what the split avoids.
#[test]
fn the_client_keeps_to_the_limits_of_aslmps_simulated_fx5u() {
    let Some(python) = venv_python() else { return };
    let server = Aslmp::start(&python, "fx5u-32mt-ds");
    for (entry, code) in [("tcp", Code::Binary), ("tcp-ascii", Code::Ascii)] {
        let settings = family_client(server.address(entry), Family::Fx5, FrameKind::E3, code);
        let batch = settings.limits.batch_words;
        let points = settings.limits.random_points;
        let mut c = Client::new(settings.clone());
        let name = c.type_name().unwrap_or_else(|e| panic!("{code}: {e}"));
        assert_eq!(
            (name.name.as_str(), name.code),
            ("FX5U-32MT/DS", 0x4A49),
            "{code}"
        );
        let head = Device::new("D", 1000);
        let words: Vec<u16> = (0..961u16).map(|i| i.wrapping_mul(37) ^ 0x5A00).collect();
        let fence = WriteFence::new(vec![WordRange::new("D", 1000, 1960)]);
        let writes = fence.writes(batch, &head, &words).expect("inside");
        assert_eq!(writes.len(), 961usize.div_ceil(batch), "{code}");
        for w in &writes {
            c.write(w).unwrap_or_else(|e| panic!("{code}: {e}"));
        }
        let back = c
            .read_words(&head, 961)
            .unwrap_or_else(|e| panic!("{code}: {e}"));
        assert_eq!(back, words, "{code}");
        let many: Vec<Device> = (0..points as u32)
            .map(|i| Device::new("D", 1000 + i))
            .collect();
        let read = c
            .random_read(&many)
            .unwrap_or_else(|e| panic!("{code}: {e}"));
        assert_eq!(read, words[..points], "{code}");
        // The limit is the server's: past it, the batch is refused (binary code's 960 is also
        // the most a request can encode). An FX5U takes one connection a port at a time.
        drop(c);
        if batch >= 960 {
            continue;
        }
        let mut over = settings.clone();
        over.limits.batch_words = batch + 1;
        over.read_retries = 0;
        let e = Client::new(over)
            .read_words(&head, batch as u32 + 1)
            .expect_err("over the limit");
        assert!(
            matches!(e, ClientError::EndCode { code: 0xC052, .. }),
            "{code}: {e}"
        );
    }
}

/// plc-comm-slmp, a second independent client (binary code only), against the simulated CPU
/// as an iQ-F port: the type name and model code, the program's signature, a write read back.
#[test]
fn plc_comm_slmp_talks_to_the_simulated_cpu() {
    let Some(python) = venv_python() else { return };
    let project = session();
    let (manifest, head) = generated_with_head(&project, "mitsubishi-fx5", "fx5u");
    let sim = slmp_simulator(&project, &manifest, "fx5u", "FX5U-32MT/DS", |_| {});
    let script = format!(
        "from slmp.client import SlmpClient\n\
         from slmp import SlmpTarget\n\
         t = SlmpTarget(network=0, station=0xFF, module_io=0x03FF, multidrop=0)\n\
         with SlmpClient('127.0.0.1', {port}, transport='tcp', plc_profile='melsec:iq-f', default_target=t) as c:\n\
         \x20   info = c.read_type_name()\n\
         \x20   print(info.model, hex(info.model_code))\n\
         \x20   print(list(c.read_devices('{head}', 3, bit_unit=False)))\n\
         \x20   c.write_devices('D100', [1, 2, 65535], bit_unit=False)\n\
         \x20   print(list(c.read_devices('D100', 3, bit_unit=False)))\n",
        port = sim.address().port(),
    );
    let out = Command::new(&python)
        .args(["-c", &script])
        .output()
        .expect("python runs");
    let stdout = succeeded(&out, "");
    assert_eq!(
        stdout, "FX5U-32MT/DS 0x4a49\n[17232, 18760, 2]\n[1, 2, 65535]\n",
        "the signature reads as the program writes it"
    );
    assert_eq!(sim.read(&Device::new("D", 102)), 0xFFFF);
    assert!(sim.audit().stray_writes.is_empty());
}

/// A live run against aslmp's simulated CPUs, with the test program's behaviour scanning their
/// memory over a second port ([`RemoteProgram`]): the live backend talks to the third-party
/// server in binary and in ASCII code, in its frames and within its limits, and every trial it
/// runs gets the built-in model's verdict; `hil doctor` through the binary finds the bench
/// ready in the same codes.
#[rstest::rstest]
#[case::fx5u_binary(
    "fx5u-32mt-ds",
    "mitsubishi-fx5",
    "fx5u",
    "tcp",
    Code::Binary,
    FrameKind::E3,
    "tcp-4e"
)]
#[case::fx5u_ascii(
    "fx5u-32mt-ds",
    "mitsubishi-fx5",
    "fx5u",
    "tcp-ascii",
    Code::Ascii,
    FrameKind::E3,
    "tcp-4e"
)]
#[case::r04cpu_binary(
    "r04cpu",
    "mitsubishi-iqr",
    "rcpu",
    "tcp-4e",
    Code::Binary,
    FrameKind::E4,
    "tcp"
)]
#[case::r04cpu_ascii(
    "r04cpu",
    "mitsubishi-iqr",
    "rcpu",
    "tcp-ascii",
    Code::Ascii,
    FrameKind::E3,
    "tcp"
)]
fn a_live_run_against_aslmps_simulated_cpu(
    #[case] target: &str,
    #[case] profile: &str,
    #[case] variant: &str,
    #[case] entry: &str,
    #[case] code: Code,
    #[case] frame: FrameKind,
    #[case] program_entry: &str,
) {
    let Some(python) = venv_python() else { return };
    let server = Aslmp::start(&python, target);
    let mut project = session();
    let manifest = generated(&project, profile, variant);
    let family = Family::of_profile(profile);
    let (type_name, model_code) = match family {
        Family::Fx5 => ("FX5U-32MT/DS", 0x4A49),
        Family::Iqr => ("R04CPU", 0x4800),
    };
    let model = reference(&project, profile);
    let program = RemoteProgram::start(
        SlmpSimSettings::new(manifest.clone(), variant, type_name),
        project.profiles.get(profile).cloned().expect("profile"),
        model.clone(),
        family_client(
            server.address(program_entry),
            family,
            if program_entry == "tcp-4e" {
                FrameKind::E4
            } else {
                FrameKind::E3
            },
            Code::Binary,
        ),
    )
    .expect("the program scans");
    let dir = scratch();
    let file = dir.path().join("manifest.json");
    std::fs::write(
        &file,
        serde_json::to_string_pretty(&manifest).expect("json"),
    )
    .expect("write");
    let code_key = match code {
        Code::Binary => "binary",
        Code::Ascii => "ascii",
    };
    let frame_key = match frame {
        FrameKind::E3 => "3e",
        FrameKind::E4 => "4e",
    };
    let spec = format!(
        "slmp:aslmp={}?manifest={}&confirm={type_name}&sandbox=manifest&code={code_key}&frame={frame_key}",
        server.address(entry),
        file.display()
    );
    // The doctor first (an FX5U takes one connection a port at a time), on the bench the
    // `--backend` text names, as `hil doctor` reads it.
    let settings = crate::backend::bench_settings(&spec, Path::new("."), &project.profiles)
        .unwrap_or_else(|e| panic!("{spec}: {e}"))
        .expect("a live backend");
    let (findings, _) = doctor(&settings);
    for f in &findings {
        assert!(f.result.is_ok(), "{}: {:?}", f.what, f.result);
    }
    assert!(
        findings.iter().any(|f| f.what == "program signature"),
        "{:?}",
        findings.iter().map(|f| f.what).collect::<Vec<_>>()
    );
    let sandbox = fence::parse_ranges(&manifest.writes.join(","), &ADDRESSING).expect("writes");
    let mut s = SlmpBench::new(
        "aslmp",
        server.address(entry),
        manifest.clone(),
        variant,
        type_name,
        sandbox,
    );
    s.link.frame = frame;
    s.link.code = code;
    s.fit_limits();
    s.case_timeout = Duration::from_secs(5);
    let backend = Arc::new(BenchBackend::new(s, &project.profiles).expect("backend"));
    backend
        .connect()
        .unwrap_or_else(|e| panic!("interlocks: {e}"));
    assert!(
        backend.describe().contains(&format!("({model_code:04X}H)")),
        "{}",
        backend.describe()
    );
    let live: Arc<dyn Backend> = backend.clone();
    project.backends.push(live.clone());
    // Every 12th trial the program can hold: pulse forms, errors and both fills among them.
    let trials: Vec<Trial> = runnable(&project, &live).step_by(12).collect();
    assert!(trials.len() > 8, "{}", trials.len());
    let expected: Vec<Trial> = project
        .plan(std::slice::from_ref(&model))
        .into_iter()
        .filter(|t| t.variant == variant)
        .collect();
    let want = verdicts(&expected);
    let got = verdicts(&trials);
    for (t, v) in trials.iter().zip(&got) {
        let i = expected
            .iter()
            .position(|e| e.check_name() == t.check_name() && e.case_id() == t.case_id())
            .unwrap_or_else(|| panic!("{}: not a model trial", t.name()));
        assert_eq!(v, &want[i], "{} ({code})", t.name());
    }
    assert!(program.audit().executions > 0);
}
