//! The GPU tests run with the validation layer's synchronization validation on
//! (VK_EXT_validation_features; `SPECULA_SYNC_VALIDATION=0` turns it off): this test shows
//! that it sees hazards, with two unsynchronised copies into one buffer. (Layer 1.3.239, as
//! on Debian 12, tracks transfers, compute and descriptor accesses; it does not yet track
//! dynamic-rendering attachments, which the recorder's declared reads and writes cover.)

mod common;

use ash::vk;
use specula::vk::{Buffer, MemoryLocation};

#[test]
fn synchronization_validation_reports_a_write_after_write() {
    if std::env::var("SPECULA_SYNC_VALIDATION").is_ok_and(|v| v == "0") {
        return;
    }
    let ctx = common::gpu();
    let usage = vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST;
    let mut a = Buffer::new(&ctx, "sync.a", 1024, usage, MemoryLocation::GpuOnly).unwrap();
    let mut b = Buffer::new(&ctx, "sync.b", 1024, usage, MemoryLocation::GpuOnly).unwrap();
    ctx.one_shot(|cmd| {
        let r = [vk::BufferCopy { src_offset: 0, dst_offset: 0, size: 1024 }];
        unsafe {
            ctx.device.cmd_copy_buffer(cmd, a.raw, b.raw, &r);
            ctx.device.cmd_copy_buffer(cmd, a.raw, b.raw, &r);
        }
        Ok(())
    })
    .unwrap();
    let messages = ctx.validation.error_messages();
    assert_eq!(ctx.validation.error_count(), 1, "{messages:#?}");
    assert!(messages[0].contains("SYNC-HAZARD-WRITE-AFTER-WRITE") && messages[0].contains("sync.b"), "{messages:#?}");
    a.destroy(&ctx);
    b.destroy(&ctx);
}
