#![no_main]
// The glTF / GLB importer: no panic, no "internal error", a scene that validates.
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Some(finding) = specula::fuzzing::gltf(data) {
        panic!("{finding}");
    }
});
