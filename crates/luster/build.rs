//! With the `oidn` feature and an Open Image Denoise found through
//! `OIDN_DIR`, records `OIDN_DIR/lib` as the run path of luster's binaries
//! and tests, so they load the library they were linked against without
//! `LD_LIBRARY_PATH`. A default build, or an OIDN found by pkg-config in a
//! system folder, needs nothing here.

fn main() {
    println!("cargo:rerun-if-env-changed=OIDN_DIR");
    if std::env::var_os("CARGO_FEATURE_OIDN").is_none() {
        return;
    }
    let Some(dir) = std::env::var_os("OIDN_DIR").filter(|d| !d.is_empty()) else {
        return;
    };
    let target = std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    if target == "linux" || target == "macos" {
        let lib = std::path::Path::new(&dir).join("lib");
        println!("cargo:rustc-link-arg=-Wl,-rpath,{}", lib.display());
    }
}
