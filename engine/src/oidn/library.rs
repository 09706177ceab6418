//! Loading Intel Open Image Denoise at run time and the few C functions raykin calls.
//!
//! Why dlopen and not the `oidn` crate: that crate links `libOpenImageDenoise` when the binary is built, so a
//! binary whose library is missing dies in the system loader before `main` runs, and no message or fallback
//! is possible. It has no run-time loading feature; a `libloading` table of the two dozen functions below does the
//! same job and turns a missing or broken library into an [`OidnError`] the caller can report and fall back
//! from. The build then needs neither the library nor its headers.
//!
//! Where the library is looked for, in order ([`search_dirs`]):
//! 1. `$RAYKIN_OIDN_DIR` alone when it is set (the folder holding `libOpenImageDenoise.so.2`);
//! 2. the checkout's `.oidn/lib`, where `scripts/setup.sh` unpacks the PyPI wheel (baked in at build time,
//!    like an rpath);
//! 3. `oidn/` beside the executable, then the executable's own folder (a copied install);
//! 4. the system loader's own search (`LD_LIBRARY_PATH`, ldconfig).

use super::OidnError;
use std::ffi::{CStr, c_char, c_int, c_void};
use std::path::{Path, PathBuf};

/// The variable that names the folder holding the library; when set, nothing else is searched.
pub const DIR_VARIABLE: &str = "RAYKIN_OIDN_DIR";

/// The library's file name on this platform (its major version is part of the ABI).
pub const LIBRARY_FILE: &str = if cfg!(target_os = "windows") {
    "OpenImageDenoise.dll"
} else if cfg!(target_os = "macos") {
    "libOpenImageDenoise.2.dylib"
} else {
    "libOpenImageDenoise.so.2"
};

/// Where `scripts/setup.sh` unpacks the libraries: `.oidn/lib` in the checkout this binary was built from.
pub fn project_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../.oidn/lib")
}

/// The folders searched, in order, before the system loader's own search (module docs).
pub fn search_dirs() -> Vec<PathBuf> {
    if let Some(dir) = std::env::var_os(DIR_VARIABLE).filter(|d| !d.is_empty()) {
        return vec![PathBuf::from(dir)];
    }
    let mut dirs = vec![project_dir()];
    if let Some(exe_dir) = std::env::current_exe()
        .ok()
        .and_then(|e| e.parent().map(Path::to_path_buf))
    {
        dirs.push(exe_dir.join("oidn"));
        dirs.push(exe_dir);
    }
    dirs
}

pub type Device = *mut c_void;
pub type Buffer = *mut c_void;
pub type Filter = *mut c_void;

/// `OIDNDeviceType` values.
pub const DEVICE_TYPE_CPU: c_int = 1;
pub const DEVICE_TYPE_SYCL: c_int = 2;
pub const DEVICE_TYPE_CUDA: c_int = 3;
pub const DEVICE_TYPE_HIP: c_int = 4;
pub const DEVICE_TYPE_METAL: c_int = 5;
/// `OIDN_STORAGE_HOST`: host memory the device can read and write (pinned memory on GPUs).
pub const STORAGE_HOST: c_int = 1;
/// `OIDN_EXTERNAL_MEMORY_TYPE_FLAG_OPAQUE_FD`: a POSIX file descriptor of memory another API (Vulkan) exported.
pub const EXTERNAL_MEMORY_OPAQUE_FD: c_int = 1;
/// `OIDN_FORMAT_FLOAT3`.
pub const FORMAT_FLOAT3: c_int = 3;
/// `OIDN_ERROR_NONE`.
pub const ERROR_NONE: c_int = 0;

/// The loaded library's entry points. Built once per folder and never unloaded: OIDN's CPU device keeps TBB
/// worker threads that must not outlive their code.
pub struct Library {
    /// The file that was loaded (or the bare file name when the system loader found it).
    pub path: PathBuf,
    pub get_num_physical_devices: unsafe extern "C" fn() -> c_int,
    pub get_physical_device_int: unsafe extern "C" fn(c_int, *const c_char) -> c_int,
    pub get_physical_device_bool: unsafe extern "C" fn(c_int, *const c_char) -> bool,
    pub get_physical_device_string: unsafe extern "C" fn(c_int, *const c_char) -> *const c_char,
    pub new_device: unsafe extern "C" fn(c_int) -> Device,
    pub new_device_by_id: unsafe extern "C" fn(c_int) -> Device,
    pub set_device_int: unsafe extern "C" fn(Device, *const c_char, c_int),
    pub get_device_int: unsafe extern "C" fn(Device, *const c_char) -> c_int,
    pub commit_device: unsafe extern "C" fn(Device),
    pub get_device_error: unsafe extern "C" fn(Device, *mut *const c_char) -> c_int,
    pub sync_device: unsafe extern "C" fn(Device),
    pub release_device: unsafe extern "C" fn(Device),
    pub new_buffer: unsafe extern "C" fn(Device, usize) -> Buffer,
    pub new_buffer_with_storage: unsafe extern "C" fn(Device, usize, c_int) -> Buffer,
    pub get_buffer_data: unsafe extern "C" fn(Buffer) -> *mut c_void,
    pub new_shared_buffer_from_fd: unsafe extern "C" fn(Device, c_int, c_int, usize) -> Buffer,
    pub write_buffer: unsafe extern "C" fn(Buffer, usize, usize, *const c_void),
    pub read_buffer: unsafe extern "C" fn(Buffer, usize, usize, *mut c_void),
    pub release_buffer: unsafe extern "C" fn(Buffer),
    pub new_filter: unsafe extern "C" fn(Device, *const c_char) -> Filter,
    #[allow(clippy::type_complexity)]
    pub set_filter_image: unsafe extern "C" fn(
        Filter,
        *const c_char,
        Buffer,
        c_int,
        usize,
        usize,
        usize,
        usize,
        usize,
    ),
    pub set_filter_bool: unsafe extern "C" fn(Filter, *const c_char, bool),
    pub set_filter_int: unsafe extern "C" fn(Filter, *const c_char, c_int),
    pub set_filter_float: unsafe extern "C" fn(Filter, *const c_char, f32),
    pub commit_filter: unsafe extern "C" fn(Filter),
    pub execute_filter: unsafe extern "C" fn(Filter),
    pub release_filter: unsafe extern "C" fn(Filter),
}

impl Library {
    /// The library from the first place of [`search_dirs`] (then the system loader) that holds a loadable
    /// copy; loaded once per process. The error lists every place tried and why it failed.
    pub fn shared() -> Result<&'static Library, OidnError> {
        use std::sync::OnceLock;
        static SHARED: OnceLock<Result<&'static Library, OidnError>> = OnceLock::new();
        SHARED.get_or_init(Self::search).clone()
    }

    fn search() -> Result<&'static Library, OidnError> {
        let mut tried = Vec::new();
        for dir in search_dirs() {
            match Self::open_in(&dir) {
                Ok(lib) => return Ok(lib),
                Err(e) => tried.push(e.to_string()),
            }
        }
        if std::env::var_os(DIR_VARIABLE).is_none_or(|d| d.is_empty()) {
            match Self::open_file(Path::new(LIBRARY_FILE)) {
                Ok(lib) => return Ok(lib),
                Err(e) => tried.push(format!("the system library path: {e}")),
            }
        }
        Err(OidnError::LibraryNotFound { tried })
    }

    /// The library in `dir` (no other place is tried); loaded once per folder.
    pub fn open_in(dir: &Path) -> Result<&'static Library, OidnError> {
        let file = dir.join(LIBRARY_FILE);
        if !file.is_file() {
            return Err(OidnError::Load {
                path: file.display().to_string(),
                reason: "no such file".into(),
            });
        }
        Self::open_file(&file)
    }

    #[cfg(feature = "oidn")]
    fn open_file(file: &Path) -> Result<&'static Library, OidnError> {
        use std::collections::HashMap;
        use std::sync::Mutex;
        static LOADED: Mutex<Option<HashMap<PathBuf, &'static Library>>> = Mutex::new(None);
        let mut loaded = LOADED.lock().unwrap_or_else(|p| p.into_inner());
        let loaded = loaded.get_or_insert_with(HashMap::new);
        if let Some(lib) = loaded.get(file) {
            return Ok(lib);
        }
        let lib: &'static Library = Box::leak(Box::new(load_symbols(file)?));
        loaded.insert(file.to_path_buf(), lib);
        Ok(lib)
    }

    #[cfg(not(feature = "oidn"))]
    fn open_file(_file: &Path) -> Result<&'static Library, OidnError> {
        Err(OidnError::NotBuilt)
    }

    /// The device's error since the last call, if any (clears it). `device` may be null: the error of a
    /// failed device creation.
    pub(crate) fn take_error(&self, device: Device) -> Option<String> {
        let mut message: *const c_char = std::ptr::null();
        // SAFETY: `device` is null or a live device; OIDN writes a string valid until the next call.
        let code = unsafe { (self.get_device_error)(device, &mut message) };
        if code == ERROR_NONE {
            return None;
        }
        let text = if message.is_null() {
            String::new()
        } else {
            // SAFETY: a NUL-terminated string from OIDN, copied before any other call.
            unsafe { CStr::from_ptr(message) }
                .to_string_lossy()
                .into_owned()
        };
        Some(format!("{} (error {code})", text.trim()))
    }
}

/// A C string for a parameter name (all are static ASCII literals).
pub fn name(s: &'static CStr) -> *const c_char {
    s.as_ptr()
}

#[cfg(feature = "oidn")]
fn load_symbols(file: &Path) -> Result<Library, OidnError> {
    let load_error = |reason: String| OidnError::Load {
        path: file.display().to_string(),
        reason,
    };
    // SAFETY: loading runs OIDN's initialisers, which only register its device modules.
    let lib = unsafe { libloading::Library::new(file.as_os_str()) }
        .map_err(|e| load_error(e.to_string()))?;
    // The handle is leaked on purpose: the function pointers below must stay valid for the process.
    let lib: &'static libloading::Library = Box::leak(Box::new(lib));
    macro_rules! symbol {
        ($name:literal) => {{
            // SAFETY: the declared type matches OIDN 2.x's C prototype of this function (oidn.h).
            let s = unsafe { lib.get(concat!($name, "\0").as_bytes()) }.map_err(|_| {
                load_error(format!(
                    "it has no `{}` function: not Open Image Denoise 2.x",
                    $name
                ))
            })?;
            *s
        }};
    }
    Ok(Library {
        path: file.to_path_buf(),
        get_num_physical_devices: symbol!("oidnGetNumPhysicalDevices"),
        get_physical_device_int: symbol!("oidnGetPhysicalDeviceInt"),
        get_physical_device_bool: symbol!("oidnGetPhysicalDeviceBool"),
        get_physical_device_string: symbol!("oidnGetPhysicalDeviceString"),
        new_device: symbol!("oidnNewDevice"),
        new_device_by_id: symbol!("oidnNewDeviceByID"),
        set_device_int: symbol!("oidnSetDeviceInt"),
        get_device_int: symbol!("oidnGetDeviceInt"),
        commit_device: symbol!("oidnCommitDevice"),
        get_device_error: symbol!("oidnGetDeviceError"),
        sync_device: symbol!("oidnSyncDevice"),
        release_device: symbol!("oidnReleaseDevice"),
        new_buffer: symbol!("oidnNewBuffer"),
        new_buffer_with_storage: symbol!("oidnNewBufferWithStorage"),
        get_buffer_data: symbol!("oidnGetBufferData"),
        new_shared_buffer_from_fd: symbol!("oidnNewSharedBufferFromFD"),
        write_buffer: symbol!("oidnWriteBuffer"),
        read_buffer: symbol!("oidnReadBuffer"),
        release_buffer: symbol!("oidnReleaseBuffer"),
        new_filter: symbol!("oidnNewFilter"),
        set_filter_image: symbol!("oidnSetFilterImage"),
        set_filter_bool: symbol!("oidnSetFilterBool"),
        set_filter_int: symbol!("oidnSetFilterInt"),
        set_filter_float: symbol!("oidnSetFilterFloat"),
        commit_filter: symbol!("oidnCommitFilter"),
        execute_filter: symbol!("oidnExecuteFilter"),
        release_filter: symbol!("oidnReleaseFilter"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_empty_folder_names_the_missing_file() {
        let dir = std::env::temp_dir().join(format!("raykin-oidn-empty-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let err = Library::open_in(&dir).err().expect("nothing to load");
        let text = err.to_string();
        assert!(
            text.contains(LIBRARY_FILE) && text.contains("no such file"),
            "{text}"
        );
        let _ = std::fs::remove_dir(&dir);
    }

    #[cfg(feature = "oidn")]
    #[test]
    fn a_file_that_is_not_a_library_is_refused_with_the_loader_reason() {
        let dir = std::env::temp_dir().join(format!("raykin-oidn-bogus-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join(LIBRARY_FILE), b"not an ELF file").unwrap();
        let text = Library::open_in(&dir).err().expect("garbage").to_string();
        assert!(text.contains(LIBRARY_FILE), "{text}");
        assert!(!text.contains("no such file"), "{text}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
