#![no_main]
// The C ABI's struct parsing: random calls on one context (lavapipe: SPECULA_DEVICE=llvmpipe).
use std::sync::OnceLock;

use specula::ffi::*;

struct Ctx(*mut SpeculaContext);
unsafe impl Send for Ctx {}
unsafe impl Sync for Ctx {}

fn context() -> &'static Ctx {
    static CTX: OnceLock<Ctx> = OnceLock::new();
    CTX.get_or_init(|| {
        let desc = SpeculaContextDesc {
            r#type: SPECULA_STRUCT_CONTEXT_DESC,
            size: std::mem::size_of::<SpeculaContextDesc>() as u32,
            device_name: std::ptr::null(),
            enable_validation: 0,
        };
        let mut ctx = std::ptr::null_mut();
        unsafe { assert_eq!(specula_context_create(&desc, &mut ctx), SPECULA_SUCCESS) };
        Ctx(ctx)
    })
}

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Some(finding) = unsafe { specula::fuzzing::c_abi(context().0, data) } {
        panic!("{finding}");
    }
});
