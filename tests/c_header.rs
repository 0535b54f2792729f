//! include/specula.h is what cbindgen generates from src/ffi/ today (a stale header fails
//! this test). Regenerate with `SPECULA_UPDATE_HEADER=1 cargo test --test c_header`.

#[test]
fn header_is_current() {
    let root = env!("CARGO_MANIFEST_DIR");
    let config = cbindgen::Config::from_file(format!("{root}/cbindgen.toml")).unwrap();
    let mut generated = Vec::new();
    cbindgen::Builder::new()
        .with_src(format!("{root}/src/ffi/mod.rs"))
        .with_config(config)
        .generate()
        .expect("cbindgen")
        .write(&mut generated);
    let path = format!("{root}/include/specula.h");
    if std::env::var_os("SPECULA_UPDATE_HEADER").is_some() {
        std::fs::write(&path, &generated).unwrap();
    }
    let checked_in = std::fs::read(&path).unwrap_or_default();
    assert!(checked_in == generated, "include/specula.h is stale: run SPECULA_UPDATE_HEADER=1 cargo test --test c_header");
}
