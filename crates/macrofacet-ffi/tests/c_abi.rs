//! The C ABI test `tests/c/abi_test.c` (the program ctest runs as `abi_test_c`), built and run by
//! `cargo test` too: compiled with the system C compiler (found by the `cc` crate, with the
//! warnings of cmake/AbiTests.cmake) against the static library cargo built for this test, and
//! linked with the system libraries rustc reports for a Rust staticlib.

use std::path::{Path, PathBuf};
use std::process::Command;

const WORKSPACE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");

/// The `host:` line of `rustc -vV`: tests run on the machine they are built for.
fn host_triple(rustc: &str) -> String {
    let out = Command::new(rustc).arg("-vV").output().expect("run rustc -vV");
    let text = String::from_utf8(out.stdout).expect("rustc -vV prints UTF-8");
    text.lines().find_map(|l| l.strip_prefix("host: ")).expect("rustc -vV names its host").trim().to_owned()
}

/// What rustc prints as the `native-static-libs` of an empty staticlib (as
/// cmake/NativeStaticLibs.cmake does): the system libraries Rust's std needs (`-lgcc_s -lm ...`).
fn native_static_libs(rustc: &str, dir: &Path) -> Vec<String> {
    let source = dir.join("empty.rs");
    std::fs::write(&source, "").unwrap();
    let out = Command::new(rustc)
        .args(["--crate-type", "staticlib", "--crate-name", "mf_native_libs", "--print", "native-static-libs", "--out-dir"])
        .arg(dir)
        .arg(&source)
        .output()
        .expect("run rustc --print native-static-libs");
    let text = String::from_utf8_lossy(&out.stderr);
    let line = text.lines().find_map(|l| l.split_once("native-static-libs: ").map(|(_, libs)| libs));
    line.expect("rustc reports the native static libs").split_whitespace().map(str::to_owned).collect()
}

/// libmacrofacet_ffi.a as cargo built it for this test run: next to the test binary's `deps/`.
fn static_library() -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let deps = exe.parent().unwrap();
    let name = "libmacrofacet_ffi.a";
    [deps.join(name), deps.parent().unwrap().join(name)]
        .into_iter()
        .find(|p| p.exists())
        .unwrap_or_else(|| panic!("{name} not found next to {}", deps.display()))
}

#[test]
#[cfg(unix)]
fn c_abi_test_program_passes() {
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let host = host_triple(&rustc);
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("c_abi");
    std::fs::create_dir_all(&dir).unwrap();
    let exe = dir.join("abi_test_c");

    let compiler = cc::Build::new().target(&host).host(&host).opt_level(2).debug(false).cargo_metadata(false).get_compiler();
    let mut compile = compiler.to_command();
    compile
        .args(["-std=c11", "-Wall", "-Wextra", "-Werror", "-pedantic", "-I"])
        .arg(Path::new(WORKSPACE).join("include"))
        .arg(Path::new(WORKSPACE).join("tests/c/abi_test.c"))
        .arg(static_library())
        .args(native_static_libs(&rustc, &dir))
        .arg("-lm")
        .arg("-o")
        .arg(&exe);
    let built = compile.output().expect("run the C compiler");
    assert!(built.status.success(), "compiling tests/c/abi_test.c failed:\n{compile:?}\n{}", String::from_utf8_lossy(&built.stderr));

    let run = Command::new(&exe).output().expect("run abi_test_c");
    let stdout = String::from_utf8_lossy(&run.stdout);
    let stderr = String::from_utf8_lossy(&run.stderr);
    print!("{stdout}");
    assert!(run.status.success(), "tests/c/abi_test.c failed ({}):\n{stdout}\n{stderr}", run.status);
}
