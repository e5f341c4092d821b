//! Finds Embree 3 (pkg-config `embree3`, else the standard include directories),
//! generates its bindings with bindgen (with bindgen's layout checks of every FFI struct)
//! and, with the feature `bench`, compiles the C reference benchmark.
//!
//! Failures end the build with one line naming the Debian package to install. Embree 4
//! alone is one of them: it has no ray streams and another query API.

use std::path::{Path, PathBuf};
use std::process::{exit, Command};

/// Where Embree's headers and library are: include and library search directories.
struct Embree {
    include_dirs: Vec<PathBuf>,
    lib_dirs: Vec<PathBuf>,
}

/// Include directories searched when pkg-config knows no Embree (Debian's libembree-dev
/// ships no .pc file).
const INCLUDE_DIRS: [&str; 3] = [
    "/usr/include",
    "/usr/local/include",
    "/opt/homebrew/include",
];

fn fail(message: &str) -> ! {
    eprintln!("luxtally: {message}");
    // Also as a warning, so it shows up even when cargo hides the script's stderr.
    println!("cargo:warning=luxtally: {message}");
    exit(1);
}

/// `pkg-config` for one package, if the command and a .pc file exist.
fn from_pkg_config(package: &str) -> Option<Embree> {
    let out = Command::new("pkg-config")
        .args(["--cflags-only-I", "--libs-only-L", package])
        .output()
        .ok()?;
    if !out.status.success() {
        return None;
    }
    let text = String::from_utf8_lossy(&out.stdout);
    let mut e = Embree {
        include_dirs: Vec::new(),
        lib_dirs: Vec::new(),
    };
    for flag in text.split_whitespace() {
        if let Some(dir) = flag.strip_prefix("-I") {
            e.include_dirs.push(dir.into());
        } else if let Some(dir) = flag.strip_prefix("-L") {
            e.lib_dirs.push(dir.into());
        }
    }
    Some(e)
}

/// The first include directory holding `<sub>/rtcore.h`.
fn headers_in(sub: &str) -> Option<PathBuf> {
    INCLUDE_DIRS
        .iter()
        .map(Path::new)
        .find(|dir| dir.join(sub).join("rtcore.h").is_file())
        .map(Path::to_path_buf)
}

/// Embree 3; else, when only Embree 4 is there, the build stops saying so.
fn find_embree() -> Option<Embree> {
    if let Some(e) = from_pkg_config("embree3") {
        return Some(e);
    }
    if let Some(dir) = headers_in("embree3") {
        return Some(Embree {
            include_dirs: vec![dir],
            lib_dirs: Vec::new(),
        });
    }
    let embree4 = from_pkg_config("embree4")
        .map(|_| "pkg-config embree4".to_string())
        .or_else(|| headers_in("embree4").map(|d| d.join("embree4").display().to_string()));
    if let Some(found) = embree4 {
        fail(&format!(
            "found only Embree 4 ({found}); luxtally supports Embree 3.x only \
             (Debian 12's libembree-dev, 3.13): install it with `apt-get install -y libembree-dev`"
        ));
    }
    None
}

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=ffi/embree.h");
    println!("cargo:rerun-if-changed=benches/c/embree_reference.c");

    let Some(embree) = find_embree() else {
        fail("Embree 3 not found: install it with `apt-get install -y libembree-dev`");
    };
    for dir in &embree.lib_dirs {
        println!("cargo:rustc-link-search=native={}", dir.display());
    }
    println!("cargo:rustc-link-lib=dylib=embree3");

    // Bindings. bindgen panics when it cannot load libclang: turn that into our message.
    let mut builder = bindgen::Builder::default()
        .header("ffi/embree.h")
        .allowlist_function("rtc.*")
        .allowlist_type("RTC.*")
        .allowlist_var("RTC.*")
        .derive_default(true)
        // Constants as `RTC_BUILD_QUALITY_HIGH`, not `RTCBuildQuality_RTC_BUILD_QUALITY_HIGH`.
        .prepend_enum_name(false)
        // Size, alignment and field offsets of every struct checked against clang's: the
        // cheapest guard against ABI drift. bindgen emits them as compile-time assertions
        // (`const _: () = ...` in `accel::embree::sys`), so every build of the lib checks them.
        .layout_tests(true);
    for dir in &embree.include_dirs {
        builder = builder.clang_arg(format!("-I{}", dir.display()));
    }
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let generated =
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(move || builder.generate()));
    std::panic::set_hook(default_hook);
    let bindings = match generated {
        Err(_) => fail("libclang not found (bindgen needs it): install it with `apt-get install -y libclang-dev`"),
        Ok(Err(e)) => fail(&format!(
            "bindgen failed on ffi/embree.h ({e}); are the Embree headers complete? `apt-get install -y libembree-dev`"
        )),
        Ok(Ok(b)) => b,
    };
    let out = PathBuf::from(std::env::var_os("OUT_DIR").unwrap_or_default());
    if let Err(e) = bindings.write_to_file(out.join("embree_bindings.rs")) {
        fail(&format!(
            "cannot write the Embree bindings into {}: {e}",
            out.display()
        ));
    }

    // The C reference benchmark (plain loops over Embree's API), linked into the crate
    // only when a benchmark asks for it.
    if std::env::var_os("CARGO_FEATURE_BENCH").is_none() {
        return;
    }
    let mut c = cc::Build::new();
    c.file("benches/c/embree_reference.c")
        .opt_level(3)
        .warnings(true);
    for dir in &embree.include_dirs {
        c.include(dir);
    }
    c.compile("luxtally_c_reference");
}
