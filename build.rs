//! Finds Embree (pkg-config `embree4`/`embree3`, else the standard include directories),
//! generates its bindings with bindgen and compiles the C reference benchmark.
//!
//! Failures end the build with one line naming the Debian package to install.

use std::path::{Path, PathBuf};
use std::process::{exit, Command};

/// What we found: major version, include directories, library search directories.
struct Embree {
    major: u32,
    include_dirs: Vec<PathBuf>,
    lib_dirs: Vec<PathBuf>,
}

fn fail(message: &str) -> ! {
    eprintln!("luxtally: {message}");
    // Also as a warning, so it shows up even when cargo hides the script's stderr.
    println!("cargo:warning=luxtally: {message}");
    exit(1);
}

/// `pkg-config` for one package, if the command and a .pc file exist.
fn from_pkg_config(package: &str, major: u32) -> Option<Embree> {
    let out = Command::new("pkg-config")
        .args(["--cflags-only-I", "--libs-only-L", package])
        .output()
        .ok()?;
    if !out.status.success() {
        return None;
    }
    let text = String::from_utf8_lossy(&out.stdout);
    let mut e = Embree {
        major,
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

/// Reads `RTC_VERSION_MAJOR` from `<dir>/embreeN/rtcore_config.h`.
fn version_in(include_dir: &Path, sub: &str) -> Option<u32> {
    let text = std::fs::read_to_string(include_dir.join(sub).join("rtcore_config.h")).ok()?;
    let value = |name: &str| -> Option<u32> {
        text.lines().find_map(|line| {
            let mut words = line.split_whitespace();
            (words.next()? == "#define" && words.next()? == name)
                .then(|| words.next()?.parse().ok())
                .flatten()
        })
    };
    value("RTC_VERSION_MAJOR").or_else(|| value("RTC_VERSION").map(|v| v / 10000))
}

fn find_embree() -> Option<Embree> {
    if let Some(e) = from_pkg_config("embree4", 4).or_else(|| from_pkg_config("embree3", 3)) {
        return Some(e);
    }
    for dir in [
        "/usr/include",
        "/usr/local/include",
        "/opt/homebrew/include",
    ] {
        for sub in ["embree4", "embree3"] {
            if let Some(major) = version_in(Path::new(dir), sub) {
                return Some(Embree {
                    major,
                    include_dirs: vec![dir.into()],
                    lib_dirs: Vec::new(),
                });
            }
        }
    }
    None
}

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=ffi/embree.h");
    println!("cargo:rerun-if-changed=benches/c/embree_reference.c");
    println!("cargo::rustc-check-cfg=cfg(embree4)");

    let Some(embree) = find_embree() else {
        fail("Embree not found: install it with `apt-get install -y libembree-dev`");
    };
    if embree.major == 4 {
        println!("cargo:rustc-cfg=embree4");
    }
    for dir in &embree.lib_dirs {
        println!("cargo:rustc-link-search=native={}", dir.display());
    }
    println!("cargo:rustc-link-lib=dylib=embree{}", embree.major);

    // Bindings. bindgen panics when it cannot load libclang: turn that into our message.
    let mut builder = bindgen::Builder::default()
        .header("ffi/embree.h")
        .allowlist_function("rtc.*")
        .allowlist_type("RTC.*")
        .allowlist_var("RTC.*")
        .derive_default(true)
        // Constants as `RTC_BUILD_QUALITY_HIGH`, not `RTCBuildQuality_RTC_BUILD_QUALITY_HIGH`.
        .prepend_enum_name(false)
        .layout_tests(false);
    if embree.major == 4 {
        builder = builder.clang_arg("-DLUXTALLY_EMBREE4");
    }
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

    // The C reference benchmark (plain loops over Embree's API), linked into the crate.
    // Embree 4 has no streams and a different call signature: only built against 3.
    if embree.major == 3 {
        let mut c = cc::Build::new();
        c.file("benches/c/embree_reference.c")
            .opt_level(3)
            .warnings(true);
        for dir in &embree.include_dirs {
            c.include(dir);
        }
        c.compile("luxtally_c_reference");
    }
}
