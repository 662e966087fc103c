//! Build script: finds Embree (3 or 4), compiles the C shim in `wrapper/` with `cc`, generates
//! Rust bindings for the shim's header only with `bindgen`, and links `embree3` or `embree4`.
//!
//! Search order: `$EMBREE_DIR/include/embree{4,3}/rtcore.h` (libraries in `$EMBREE_DIR/lib` or
//! `lib64`), then the system include directories. Debian ships no pkg-config file for Embree 3,
//! so the headers are looked for directly. Without the `embree` feature nothing is built here.

use std::env;
use std::path::{Path, PathBuf};

const INSTALL_HINT: &str = "install Debian's Embree with `make setup` (or `sudo apt-get install libembree-dev libclang-dev`), \
     point EMBREE_DIR at an Embree 3 or 4 installation, \
     or build without Embree: `cargo build --no-default-features` (pure-Rust backend only)";

struct Embree {
    major: u32,
    include: PathBuf,
    lib_dir: Option<PathBuf>,
}

fn find_in(include: &Path, lib_dir: Option<PathBuf>) -> Option<Embree> {
    [4, 3].into_iter().find_map(|major| {
        include
            .join(format!("embree{major}/rtcore.h"))
            .is_file()
            .then(|| Embree {
                major,
                include: include.to_path_buf(),
                lib_dir: lib_dir.clone(),
            })
    })
}

fn find_embree() -> Result<Embree, String> {
    if let Some(dir) = env::var_os("EMBREE_DIR") {
        let dir = PathBuf::from(dir);
        let lib = ["lib", "lib64", "lib/x86_64-linux-gnu"]
            .iter()
            .map(|l| dir.join(l))
            .find(|p| p.is_dir());
        return find_in(&dir.join("include"), lib).ok_or_else(|| {
            format!(
                "EMBREE_DIR={} has no include/embree4/rtcore.h or include/embree3/rtcore.h",
                dir.display()
            )
        });
    }
    let target = env::var("TARGET").unwrap_or_default();
    let multiarch = target.replace("-unknown-", "-");
    let dirs = [
        PathBuf::from("/usr/local/include"),
        PathBuf::from("/usr/include"),
        PathBuf::from(format!("/usr/include/{multiarch}")),
    ];
    dirs.iter().find_map(|d| find_in(d, None)).ok_or_else(|| {
        "Embree headers (embree4/rtcore.h or embree3/rtcore.h) not found".to_string()
    })
}

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=wrapper/embree_shim.h");
    println!("cargo:rerun-if-changed=wrapper/embree_shim.c");
    println!("cargo:rerun-if-env-changed=EMBREE_DIR");
    println!("cargo::rustc-check-cfg=cfg(embree4)");
    if env::var_os("CARGO_FEATURE_EMBREE").is_none() {
        return;
    }

    let embree = match find_embree() {
        Ok(e) => e,
        Err(why) => {
            eprintln!(
                "\nerror: {why}.\n       vastocean's `embree` feature needs Embree: {INSTALL_HINT}.\n"
            );
            std::process::exit(1);
        }
    };
    println!(
        "cargo:rerun-if-changed={}",
        embree
            .include
            .join(format!("embree{}/rtcore_config.h", embree.major))
            .display()
    );
    if embree.major == 4 {
        println!("cargo:rustc-cfg=embree4");
    }

    cc::Build::new()
        .file("wrapper/embree_shim.c")
        .include(&embree.include)
        .define("VO_EMBREE_MAJOR", embree.major.to_string().as_str())
        .define("_POSIX_C_SOURCE", "200809L")
        .flag_if_supported("-std=c11")
        .warnings(true)
        .extra_warnings(true)
        .warnings_into_errors(true)
        .compile("vastocean_embree_shim");

    if let Some(lib) = &embree.lib_dir {
        println!("cargo:rustc-link-search=native={}", lib.display());
        // An Embree outside the system's library path is found at run time by the rpath.
        println!("cargo:rustc-link-arg=-Wl,-rpath,{}", lib.display());
    }
    println!("cargo:rustc-link-lib=dylib=embree{}", embree.major);

    let bindings = bindgen::Builder::default()
        .header("wrapper/embree_shim.h")
        .allowlist_function("vo_.*")
        .allowlist_type("vo_.*")
        .allowlist_var("VO_.*")
        .prepend_enum_name(false)
        .derive_default(true)
        .layout_tests(true)
        .generate()
        .unwrap_or_else(|e| {
            eprintln!("\nerror: bindgen could not read wrapper/embree_shim.h: {e}\n       {INSTALL_HINT}.\n");
            std::process::exit(1);
        });
    let out =
        PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR")).join("embree_shim.rs");
    bindings
        .write_to_file(&out)
        .expect("write bindings to OUT_DIR");
}
