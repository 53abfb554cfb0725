//! Tells hexsim how it was built, for the benchmark's configuration line: a figure measured on a
//! profile-guided build (`cargo pgo`, docs/performance.md), on one tuned for a CPU, or on another
//! profile than `release` is not the release build's, and says so.

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=CARGO_ENCODED_RUSTFLAGS");
    // the flags cargo passes rustc, separated by 0x1f
    let flags = std::env::var("CARGO_ENCODED_RUSTFLAGS").unwrap_or_default();
    let flags: Vec<&str> = flags.split('\x1f').filter(|f| !f.is_empty()).collect();
    println!("cargo:rustc-env=HEXSIM_RUSTFLAGS={}", flags.join(" "));
    // the profile's name is the folder cargo builds in (`PROFILE` says only debug or release):
    // OUT_DIR is <target>/<profile>/build/<package>-<hash>/out
    let out = std::env::var("OUT_DIR").unwrap_or_default();
    let profile = std::path::Path::new(&out)
        .ancestors()
        .nth(3)
        .and_then(|p| p.file_name())
        .and_then(|p| p.to_str())
        .unwrap_or("unknown");
    println!("cargo:rustc-env=HEXSIM_PROFILE={profile}");
}
