//! The device a calibration and a cost cache belong to.

use serde::{Deserialize, Serialize};

use crate::vk::Context;

/// A device as the cost cache knows it: PCI vendor and device ids, the driver's version
/// and its name (`VkPhysicalDeviceProperties`), and the driver's own description
/// (`VkPhysicalDeviceDriverProperties`: lavapipe reports driver version 1 whatever Mesa
/// release it is, and names the release there).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct DeviceKey {
    pub vendor: u32,
    pub device: u32,
    pub driver: u32,
    pub name: String,
    pub driver_info: String,
}

impl DeviceKey {
    /// The key of `ctx`'s device.
    pub fn of(ctx: &Context) -> DeviceKey {
        let p = &ctx.properties;
        DeviceKey {
            vendor: p.vendor_id,
            device: p.device_id,
            driver: p.driver_version,
            name: ctx.device_name.clone(),
            driver_info: ctx.driver_info.clone(),
        }
    }

    /// How files and reports name it.
    pub fn label(&self) -> String {
        format!("{} ({}) [{:04x}:{:04x} driver {:#x}]", self.name, self.driver_info, self.vendor, self.device, self.driver)
    }

    /// Its cache file's name.
    pub fn file_name(&self) -> String {
        // FNV-1a of the driver's description.
        let h = self.driver_info.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ b as u64).wrapping_mul(0x100_0000_01b3));
        format!("costs-{:04x}-{:04x}-{:08x}-{:016x}.json", self.vendor, self.device, self.driver, h)
    }
}
