//! Running `tptd-mesh`: what a run printed, and the JSON files it wrote.

use std::fs;
use std::path::Path;
use std::process::{Command, Output};

use serde_json::Value;

/// Runs `tptd-mesh` in `dir` with `args`.
pub fn run_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_tptd-mesh"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("the binary runs")
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Asserts the run succeeded, showing what it printed otherwise.
pub fn assert_ok(o: &Output) {
    assert!(
        o.status.success(),
        "exit {:?}\nstdout:\n{}\nstderr:\n{}",
        o.status,
        stdout(o),
        stderr(o)
    );
}

/// The JSON document in the file at `path`.
pub fn read_json(path: &Path) -> Value {
    serde_json::from_str(&fs::read_to_string(path).unwrap()).unwrap()
}

/// Every mesh format and encoding the writers have, as (file name, options).
pub fn mesh_outputs() -> Vec<(&'static str, tptd::io::WriteOptions)> {
    use tptd::io::msh::MshVersion;
    use tptd::io::vtu::VtuEncoding;
    let w = tptd::io::WriteOptions::default;
    vec![
        ("m41.msh", w()),
        ("m22.msh", w().with_msh_version(MshVersion::V22)),
        ("m41b.msh", w().with_msh_version(MshVersion::V41Binary)),
        ("m.inp", w()),
        ("b64.vtu", w()),
        ("zlib.vtu", w().with_vtu_encoding(VtuEncoding::Zlib)),
        ("raw.vtu", w().with_vtu_encoding(VtuEncoding::Raw)),
    ]
}
