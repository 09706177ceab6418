//! Storage buffers whose GPU memory another API can import: Vulkan memory exported as an opaque POSIX file
//! descriptor (`VK_KHR_external_memory_fd`), as CUDA's `cudaImportExternalMemory` and Open Image Denoise's
//! `oidnNewSharedBufferFromFD` take it. wgpu makes no such buffers, so they are made through wgpu-hal's Vulkan
//! device and handed to wgpu (`create_buffer_from_hal`), which then owns and frees them like its own.
//!
//! Memory is exported without a dedicated allocation (OIDN imports it without CUDA's dedicated flag); a driver
//! that only exports dedicated buffer memory is refused with a message, as is every non-Vulkan adapter.

use super::GpuContext;

/// A buffer wgpu uses like any other, and a file descriptor of its memory for another API to import.
pub struct ExportedBuffer {
    pub buffer: wgpu::Buffer,
    /// Bytes of the memory behind the buffer (at least the buffer's size): what an importer maps.
    pub allocation_size: u64,
    /// The exported memory; importing it hands it over (CUDA owns it after a successful import).
    #[cfg(unix)]
    pub fd: std::os::fd::OwnedFd,
}

/// Whether this device can export buffer memory as file descriptors at all (a Vulkan device with
/// `VK_KHR_external_memory_fd` enabled).
pub fn supported(ctx: &GpuContext) -> bool {
    cfg!(unix)
        && ctx
            .features
            .contains(wgpu::Features::VULKAN_EXTERNAL_MEMORY_FD)
}

/// A device-local storage buffer of `size` bytes (also a copy source and destination) whose memory is
/// exported as an opaque file descriptor. Errors name what the device lacks.
#[cfg(unix)]
pub fn exported_buffer(ctx: &GpuContext, label: &str, size: u64) -> Result<ExportedBuffer, String> {
    use ash::vk;
    use std::os::fd::FromRawFd;
    use wgpu::hal::api::Vulkan;

    if !supported(ctx) {
        return Err(format!(
            "the {:?} adapter `{}` cannot export memory (VK_KHR_external_memory_fd)",
            ctx.info.backend, ctx.info.name
        ));
    }
    // SAFETY: the raw handles are used only to make and bind a new buffer and its memory, which are then
    // handed to wgpu; nothing wgpu owns is touched.
    let hal = unsafe { ctx.device.as_hal::<Vulkan>() }
        .ok_or_else(|| "not a Vulkan device".to_string())?;
    let device = hal.raw_device();
    let instance = hal.shared_instance().raw_instance();
    let physical = hal.raw_physical_device();
    let handle_type = vk::ExternalMemoryHandleTypeFlags::OPAQUE_FD;
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER
        | vk::BufferUsageFlags::TRANSFER_SRC
        | vk::BufferUsageFlags::TRANSFER_DST;

    let mut properties = vk::ExternalBufferProperties::default();
    let query = vk::PhysicalDeviceExternalBufferInfo::default()
        .usage(usage)
        .handle_type(handle_type);
    // SAFETY: a valid physical device and well-formed structures.
    unsafe {
        instance.get_physical_device_external_buffer_properties(physical, &query, &mut properties)
    };
    let features = properties
        .external_memory_properties
        .external_memory_features;
    if !features.contains(vk::ExternalMemoryFeatureFlags::EXPORTABLE) {
        return Err("the driver cannot export storage-buffer memory as a file descriptor".into());
    }
    if features.contains(vk::ExternalMemoryFeatureFlags::DEDICATED_ONLY) {
        return Err("the driver exports buffer memory only as dedicated allocations".into());
    }

    let mut external = vk::ExternalMemoryBufferCreateInfo::default().handle_types(handle_type);
    let create = vk::BufferCreateInfo::default()
        .size(size)
        .usage(usage)
        .sharing_mode(vk::SharingMode::EXCLUSIVE)
        .push_next(&mut external);
    let vk_error = |what: &str, e: vk::Result| format!("{what}: {e}");
    // SAFETY: a valid device and create info; destroyed below on every error path.
    let buffer = unsafe { device.create_buffer(&create, None) }
        .map_err(|e| vk_error("creating the buffer", e))?;
    // SAFETY: `buffer` was made above and is not used by anything yet.
    let destroy_buffer = || unsafe { device.destroy_buffer(buffer, None) };
    // SAFETY: as above.
    let requirements = unsafe { device.get_buffer_memory_requirements(buffer) };
    // SAFETY: a valid physical device.
    let memory_properties = unsafe { instance.get_physical_device_memory_properties(physical) };
    let Some(type_index) = (0..memory_properties.memory_type_count).find(|&i| {
        requirements.memory_type_bits & (1 << i) != 0
            && memory_properties.memory_types[i as usize]
                .property_flags
                .contains(vk::MemoryPropertyFlags::DEVICE_LOCAL)
    }) else {
        destroy_buffer();
        return Err("no device-local memory type can hold the buffer".into());
    };
    let mut export = vk::ExportMemoryAllocateInfo::default().handle_types(handle_type);
    let allocate = vk::MemoryAllocateInfo::default()
        .allocation_size(requirements.size)
        .memory_type_index(type_index)
        .push_next(&mut export);
    // SAFETY: a valid device and allocate info; freed below on every error path, else owned by wgpu.
    let memory = match unsafe { device.allocate_memory(&allocate, None) } {
        Ok(m) => m,
        Err(e) => {
            destroy_buffer();
            return Err(vk_error("allocating exportable memory", e));
        }
    };
    let free_both = || {
        destroy_buffer();
        // SAFETY: allocated above, bound to nothing that outlives this call.
        unsafe { device.free_memory(memory, None) };
    };
    // SAFETY: both made above, the memory large enough and of a type the buffer accepts.
    if let Err(e) = unsafe { device.bind_buffer_memory(buffer, memory, 0) } {
        free_both();
        return Err(vk_error("binding the memory", e));
    }
    let fd_device = ash::khr::external_memory_fd::Device::new(instance, device);
    let get_fd = vk::MemoryGetFdInfoKHR::default()
        .memory(memory)
        .handle_type(handle_type);
    // SAFETY: the extension is enabled (checked by `supported`) and the memory was allocated exportable.
    let raw_fd = match unsafe { fd_device.get_memory_fd(&get_fd) } {
        Ok(fd) if fd >= 0 => fd,
        Ok(fd) => {
            free_both();
            return Err(format!("exporting the memory gave file descriptor {fd}"));
        }
        Err(e) => {
            free_both();
            return Err(vk_error("exporting the memory", e));
        }
    };
    // SAFETY: a new descriptor vkGetMemoryFdKHR made for the caller, owned by nothing else.
    let fd = unsafe { std::os::fd::OwnedFd::from_raw_fd(raw_fd) };
    // SAFETY: the buffer and its memory are bound and owned by nobody else; wgpu destroys and frees both when
    // the wgpu buffer is dropped and no submission uses it any more.
    let hal_buffer = unsafe {
        wgpu::hal::vulkan::Buffer::from_raw_managed(buffer, memory, 0, requirements.size)
    };
    drop(hal);
    // SAFETY: made from this device's handle with the usage and size the descriptor states; its contents are
    // whatever the importer or a pass writes (every user writes before it reads).
    let buffer = unsafe {
        ctx.device.create_buffer_from_hal::<Vulkan>(
            hal_buffer,
            &wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            },
        )
    };
    Ok(ExportedBuffer {
        buffer,
        allocation_size: requirements.size,
        fd,
    })
}

/// Where file descriptors do not exist, nothing can be exported.
#[cfg(not(unix))]
pub fn exported_buffer(
    _ctx: &GpuContext,
    _label: &str,
    _size: u64,
) -> Result<ExportedBuffer, String> {
    Err("exporting GPU memory needs POSIX file descriptors".into())
}
