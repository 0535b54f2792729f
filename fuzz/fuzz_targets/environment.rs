#![no_main]
// The environment-map loaders (EXR, HDR, PNG, JPEG by the first byte's choice).
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let Some((&which, rest)) = data.split_first() else { return };
    let ext = ["exr", "hdr", "png", "jpg"][which as usize % 4];
    let dir = std::env::temp_dir().join(format!("specula-fuzz-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    if let Some(finding) = specula::fuzzing::environment(&dir, ext, rest) {
        panic!("{finding}");
    }
});
