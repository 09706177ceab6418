//! Which OIDN device denoises: the GPU the wgpu adapter runs on when OIDN has a backend for it (CUDA for
//! NVIDIA, HIP for AMD, SYCL for Intel, Metal for Apple), else OIDN's CPU device. A GPU device that cannot
//! be created falls back to the CPU with a note, so a driver problem costs speed, not the denoiser.

use super::OidnError;
use super::library::{self, Library};
use serde::Serialize;
use std::ffi::{CStr, c_int};

/// An OIDN device type.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum DeviceKind {
    Cpu,
    Sycl,
    Cuda,
    Hip,
    Metal,
}

impl DeviceKind {
    fn from_raw(raw: c_int) -> Option<Self> {
        Some(match raw {
            library::DEVICE_TYPE_CPU => Self::Cpu,
            library::DEVICE_TYPE_SYCL => Self::Sycl,
            library::DEVICE_TYPE_CUDA => Self::Cuda,
            library::DEVICE_TYPE_HIP => Self::Hip,
            library::DEVICE_TYPE_METAL => Self::Metal,
            _ => return None,
        })
    }

    fn raw(self) -> c_int {
        match self {
            Self::Cpu => library::DEVICE_TYPE_CPU,
            Self::Sycl => library::DEVICE_TYPE_SYCL,
            Self::Cuda => library::DEVICE_TYPE_CUDA,
            Self::Hip => library::DEVICE_TYPE_HIP,
            Self::Metal => library::DEVICE_TYPE_METAL,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::Cpu => "CPU",
            Self::Sycl => "SYCL",
            Self::Cuda => "CUDA",
            Self::Hip => "HIP",
            Self::Metal => "Metal",
        }
    }
}

/// What identifies the GPU the path tracer runs on (from `wgpu::AdapterInfo`).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct AdapterIdentity {
    pub vendor: u32,
    pub name: String,
    /// `domain:bus:device.function` in hex (Vulkan's PCI bus info); empty when unknown.
    pub pci_bus_id: String,
    /// A software rasteriser (lavapipe) or a CPU adapter: the CPU device is the match.
    pub is_cpu: bool,
}

impl AdapterIdentity {
    pub fn from_wgpu(info: &wgpu::AdapterInfo) -> Self {
        Self {
            vendor: info.vendor,
            name: info.name.clone(),
            pci_bus_id: info.device_pci_bus_id.clone(),
            is_cpu: info.device_type == wgpu::DeviceType::Cpu,
        }
    }

    /// The OIDN GPU backend for this adapter's vendor; `None` for CPUs and unknown vendors.
    pub fn gpu_kind(&self) -> Option<DeviceKind> {
        if self.is_cpu {
            return None;
        }
        match self.vendor {
            0x10DE => Some(DeviceKind::Cuda),
            0x1002 => Some(DeviceKind::Hip),
            0x8086 => Some(DeviceKind::Sycl),
            0x106B => Some(DeviceKind::Metal),
            _ => None,
        }
    }

    /// `(domain, bus, device, function)` parsed from `pci_bus_id`.
    fn pci_address(&self) -> Option<[c_int; 4]> {
        let (domain, rest) = self.pci_bus_id.split_once(':')?;
        let (bus, rest) = rest.split_once(':')?;
        let (device, function) = rest.split_once('.')?;
        let hex = |s: &str| c_int::from_str_radix(s.trim(), 16).ok();
        Some([hex(domain)?, hex(bus)?, hex(device)?, hex(function)?])
    }
}

/// One of OIDN's physical devices.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PhysicalDevice {
    pub id: c_int,
    pub kind: Option<DeviceKind>,
    pub name: String,
    pub pci_address: Option<[c_int; 4]>,
}

/// OIDN's physical devices, in its order (likely fastest first).
pub fn physical_devices(lib: &Library) -> Vec<PhysicalDevice> {
    // SAFETY: plain queries with static parameter names; strings are copied at once.
    unsafe {
        let count = (lib.get_num_physical_devices)();
        (0..count.max(0))
            .map(|id| {
                let int = |n: &'static CStr| (lib.get_physical_device_int)(id, library::name(n));
                let name = (lib.get_physical_device_string)(id, library::name(c"name"));
                let pci = (lib.get_physical_device_bool)(id, library::name(c"pciAddressSupported"))
                    .then(|| {
                        [
                            int(c"pciDomain"),
                            int(c"pciBus"),
                            int(c"pciDevice"),
                            int(c"pciFunction"),
                        ]
                    });
                PhysicalDevice {
                    id,
                    kind: DeviceKind::from_raw(int(c"type")),
                    name: if name.is_null() {
                        String::new()
                    } else {
                        CStr::from_ptr(name).to_string_lossy().into_owned()
                    },
                    pci_address: pci,
                }
            })
            .collect()
    }
}

/// The physical device that is `adapter`'s GPU: same OIDN backend as the vendor, then the same PCI address,
/// else the same name, else the first of that backend (OIDN lists the likely fastest first).
pub fn matching_gpu<'a>(
    devices: &'a [PhysicalDevice],
    adapter: &AdapterIdentity,
) -> Option<&'a PhysicalDevice> {
    let kind = adapter.gpu_kind()?;
    let candidates: Vec<&PhysicalDevice> =
        devices.iter().filter(|d| d.kind == Some(kind)).collect();
    let pci = adapter.pci_address();
    candidates
        .iter()
        .find(|d| pci.is_some() && d.pci_address == pci)
        .or_else(|| {
            candidates
                .iter()
                .find(|d| d.name.eq_ignore_ascii_case(adapter.name.trim()))
        })
        .or(candidates.first())
        .copied()
}

/// A committed OIDN device.
pub struct Device {
    pub raw: library::Device,
    pub kind: DeviceKind,
    /// The physical device's name ("CPU" when OIDN names none).
    pub name: String,
}

/// Which device to open.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DeviceRequest {
    /// The GPU behind this adapter when OIDN can run on it, else the CPU.
    MatchAdapter(AdapterIdentity),
    Cpu,
}

/// Opens the requested device; returns notes for the user (a GPU that failed and the CPU used instead).
pub fn open(lib: &Library, request: &DeviceRequest) -> Result<(Device, Vec<String>), OidnError> {
    let devices = physical_devices(lib);
    let mut notes = Vec::new();
    if let DeviceRequest::MatchAdapter(adapter) = request {
        if let Some(gpu) = matching_gpu(&devices, adapter) {
            // SAFETY: `gpu.id` is one of the ids OIDN just listed.
            let raw = unsafe { (lib.new_device_by_id)(gpu.id) };
            match commit(lib, raw, gpu.kind.unwrap_or(DeviceKind::Cpu).name()) {
                Ok(()) => {
                    return Ok((
                        Device {
                            raw,
                            kind: gpu.kind.unwrap_or(DeviceKind::Cpu),
                            name: gpu.name.clone(),
                        },
                        notes,
                    ));
                }
                Err(e) => notes.push(format!("{e}; denoising on the CPU instead")),
            }
        } else if let Some(kind) = adapter.gpu_kind() {
            notes.push(format!(
                "Open Image Denoise has no {} device for `{}` (its devices: {}); denoising on the CPU",
                kind.name(),
                adapter.name,
                device_list(&devices)
            ));
        }
    }
    // SAFETY: creating a CPU device has no preconditions.
    let raw = unsafe { (lib.new_device)(DeviceKind::Cpu.raw()) };
    commit(lib, raw, "CPU")?;
    let name = devices
        .iter()
        .find(|d| d.kind == Some(DeviceKind::Cpu))
        .map_or_else(|| "CPU".to_string(), |d| d.name.clone());
    Ok((
        Device {
            raw,
            kind: DeviceKind::Cpu,
            name,
        },
        notes,
    ))
}

fn device_list(devices: &[PhysicalDevice]) -> String {
    if devices.is_empty() {
        return "none".into();
    }
    devices
        .iter()
        .map(|d| format!("{} {}", d.kind.map_or("?", DeviceKind::name), d.name))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Commits a new device, or releases it and returns OIDN's reason.
fn commit(lib: &Library, raw: library::Device, what: &str) -> Result<(), OidnError> {
    let failed = |message: String| OidnError::Device {
        device: what.to_string(),
        message,
    };
    if raw.is_null() {
        return Err(failed(
            lib.take_error(std::ptr::null_mut())
                .unwrap_or_else(|| "it could not be created".into()),
        ));
    }
    // SAFETY: `raw` is a live, uncommitted device.
    unsafe { (lib.commit_device)(raw) };
    if let Some(message) = lib.take_error(raw) {
        // SAFETY: the device is not used after this.
        unsafe { (lib.release_device)(raw) };
        return Err(failed(message));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn device(id: c_int, kind: DeviceKind, name: &str, pci: Option<[c_int; 4]>) -> PhysicalDevice {
        PhysicalDevice {
            id,
            kind: Some(kind),
            name: name.into(),
            pci_address: pci,
        }
    }

    fn nvidia(name: &str, pci: &str) -> AdapterIdentity {
        AdapterIdentity {
            vendor: 0x10DE,
            name: name.into(),
            pci_bus_id: pci.into(),
            is_cpu: false,
        }
    }

    #[test]
    fn the_adapter_gpu_is_found_by_pci_address_then_name() {
        let devices = [
            device(0, DeviceKind::Cuda, "NVIDIA H200", Some([0, 0x1b, 0, 0])),
            device(1, DeviceKind::Cuda, "NVIDIA H200", Some([0, 0x2a, 0, 0])),
            device(2, DeviceKind::Cpu, "Xeon", None),
        ];
        let by_pci = matching_gpu(&devices, &nvidia("NVIDIA H200", "0000:2a:00.0"));
        assert_eq!(by_pci.map(|d| d.id), Some(1));
        let by_name = matching_gpu(&devices, &nvidia("NVIDIA H200", ""));
        assert_eq!(by_name.map(|d| d.id), Some(0));
        let amd = AdapterIdentity {
            vendor: 0x1002,
            ..nvidia("Radeon", "")
        };
        assert_eq!(matching_gpu(&devices, &amd), None, "no HIP device listed");
        let lavapipe = AdapterIdentity {
            vendor: 0x10005,
            is_cpu: true,
            ..nvidia("llvmpipe", "")
        };
        assert_eq!(matching_gpu(&devices, &lavapipe), None);
    }

    #[test]
    fn pci_bus_ids_parse_as_hex() {
        assert_eq!(
            nvidia("x", "0001:c1:1f.7").pci_address(),
            Some([1, 0xc1, 0x1f, 7])
        );
        assert_eq!(nvidia("x", "").pci_address(), None);
        assert_eq!(nvidia("x", "zz:1:2.3").pci_address(), None);
    }
}
