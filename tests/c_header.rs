//! include/specula.h is what cbindgen generates from src/ffi/ today, with the method
//! constants generated from the registry (a stale header fails this test). Regenerate with `SPECULA_UPDATE_HEADER=1 cargo test --test c_header`.

#[test]
fn header_is_current() {
    let root = env!("CARGO_MANIFEST_DIR");
    let config = cbindgen::Config::from_file(format!("{root}/cbindgen.toml")).unwrap();
    let mut generated = Vec::new();
    cbindgen::Builder::new()
        .with_src(format!("{root}/src/ffi/mod.rs"))
        .with_config(config)
        .with_after_include(specula::docs::c_method_defines())
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

/// Every registered method is in the header once, under its registry name and number.
#[test]
fn header_names_every_method_once() {
    let header = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/include/specula.h")).unwrap();
    for m in specula::Method::ALL {
        let line = format!("#define SPECULA_METHOD_{} {}\n", specula::docs::abi_name(*m), m.abi);
        assert_eq!(header.matches(&line).count(), 1, "{line}");
    }
    assert!(header.contains(&format!("#define SPECULA_METHOD_AUTO {}", specula::methods::registry::ABI_AUTO)));
}
