//! The Embree device: one RAII handle, and the bridge from Embree's error
//! callback to [`crate::Error::Embree`].
//!
//! Embree reports failures through a per-device callback, on whatever thread
//! made the failing call. The callback here records the *first* error (code
//! and message) in a mutex that the device owns; the wrapper checks it after
//! every call that can fail (scene creation, geometry upload, commit), never
//! per ray. The callback never unwinds into C: its body runs inside
//! `catch_unwind` and takes a poisoned lock as it is.

use std::ffi::{c_char, c_void, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::ptr::NonNull;
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};

use embree_sys as sys;

use crate::isa::Isa;
use crate::{Error, Result};

/// The first error Embree reported on a device since it was last checked.
#[derive(Default)]
struct ErrorSlot {
    first: Mutex<Option<(u32, String)>>,
}

impl ErrorSlot {
    fn take(&self) -> Option<Error> {
        let mut first = self.first.lock().unwrap_or_else(PoisonError::into_inner);
        first
            .take()
            .map(|(code, message)| Error::Embree { code, message })
    }
}

/// Embree's error callback. `user` is the device's `ErrorSlot`.
unsafe extern "C" fn record_error(user: *mut c_void, code: sys::RTCError, message: *const c_char) {
    // Nothing in here may unwind into Embree's C++ frames.
    let _ = catch_unwind(AssertUnwindSafe(|| {
        if user.is_null() {
            return;
        }
        // SAFETY: `user` is the `Box<ErrorSlot>` registered in `Device::with_config`;
        // the callback is unregistered in `DeviceInner::drop` before that box is
        // freed, so the pointer is live whenever Embree calls us.
        let slot = unsafe { &*(user as *const ErrorSlot) };
        let text = if message.is_null() {
            String::from("(no message)")
        } else {
            // SAFETY: Embree passes a NUL-terminated string valid for the call.
            unsafe { CStr::from_ptr(message) }
                .to_string_lossy()
                .into_owned()
        };
        let mut first = slot.first.lock().unwrap_or_else(PoisonError::into_inner);
        if first.is_none() {
            *first = Some((code, text));
        }
    }));
}

/// What a [`Device`] and every scene made from it share.
pub(crate) struct DeviceInner {
    raw: NonNull<sys::RTCDeviceTy>,
    /// Target of the error callback's user pointer: boxed so its address is
    /// stable, owned here so it outlives every callback.
    errors: Box<ErrorSlot>,
    /// Serialises the calls that act on the device itself (object creation,
    /// geometry upload, scene commit): Embree allows concurrent ray queries,
    /// not concurrent modification of one object.
    lock: Mutex<()>,
    /// The kernel set Embree runs on this device (`None` off x86-64).
    isa: Option<Isa>,
}

// SAFETY: the device handle is only used under `lock` (object creation,
// uploads, commits) or through Embree's atomic reference counting (release in
// `drop`); the error slot is a `Mutex`. Nothing is tied to the creating thread.
unsafe impl Send for DeviceInner {}
// SAFETY: see `Send`: every shared-access path goes through `lock`, the
// `Mutex` in `errors`, or is a read of the immutable handle value.
unsafe impl Sync for DeviceInner {}

/// The kernel set a device made with `config` runs: its `isa=` item (which
/// the CPU must run), the CPU's widest capped by its `max_isa=` item, or the
/// CPU's widest. The last item of a kind wins, as in Embree's parser.
fn kernel_set_of(config: &str) -> Result<Option<Isa>> {
    let (mut pin, mut cap) = (None, None);
    for item in config.split(',') {
        match item.split_once('=').map(|(k, v)| (k.trim(), v)) {
            Some(("isa", v)) => pin = Some(v.parse::<Isa>()?.require_supported()?),
            Some(("max_isa", v)) => cap = Some(v.parse::<Isa>()?),
            _ => {}
        }
    }
    Ok(pin.or_else(|| Isa::native().map(|n| cap.map_or(n, |c| n.min(c)))))
}

impl DeviceInner {
    pub(crate) fn isa(&self) -> Option<Isa> {
        self.isa
    }

    pub(crate) fn version(&self) -> (u32, u32, u32) {
        let get = |property| {
            // SAFETY: the device is live and the VERSION_* properties exist in
            // every Embree 3 and 4, so the call cannot raise an error.
            let value = unsafe { sys::rtcGetDeviceProperty(self.raw(), property) };
            u32::try_from(value).unwrap_or(0)
        };
        (
            get(sys::RTC_DEVICE_PROPERTY_VERSION_MAJOR),
            get(sys::RTC_DEVICE_PROPERTY_VERSION_MINOR),
            get(sys::RTC_DEVICE_PROPERTY_VERSION_PATCH),
        )
    }

    pub(crate) fn raw(&self) -> sys::RTCDevice {
        self.raw.as_ptr()
    }

    /// Holds the device for a modifying call.
    pub(crate) fn lock(&self) -> MutexGuard<'_, ()> {
        self.lock.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// The first error Embree reported since the last check, as a `Result`.
    pub(crate) fn check(&self) -> Result<()> {
        match self.errors.take() {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// The recorded error if there is one, else `Error::Embree` with code 0
    /// naming the call that returned null.
    pub(crate) fn null_error(&self, what: &str) -> Error {
        self.errors.take().unwrap_or_else(|| Error::Embree {
            code: 0,
            message: format!("{what} returned null"),
        })
    }
}

impl Drop for DeviceInner {
    fn drop(&mut self) {
        // SAFETY: `raw` is a live device we hold one reference to. Unregister
        // the callback first: if Embree keeps the device alive internally,
        // it must not call into the `ErrorSlot` we are about to free.
        unsafe {
            sys::rtcSetDeviceErrorFunction(self.raw(), None, std::ptr::null_mut());
            sys::rtcReleaseDevice(self.raw());
        }
    }
}

/// An Embree device: the context every scene is created in.
///
/// Cheap to share: scenes committed from it keep it alive, so a
/// [`super::CommittedScene`] may outlive the `Device` value it came from.
#[derive(Clone)]
pub struct Device {
    pub(crate) inner: Arc<DeviceInner>,
}

impl std::fmt::Debug for Device {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (major, minor, patch) = self.version();
        f.debug_struct("Device")
            .field("raw", &self.inner.raw)
            .field("version", &format_args!("{major}.{minor}.{patch}"))
            .field("isa", &self.inner.isa)
            .finish()
    }
}

impl Device {
    /// A device with Embree's default configuration (all cores for builds),
    /// running the kernel set that [`ISA_ENV`](crate::isa::ISA_ENV) names,
    /// or the widest one the CPU has when the variable is unset.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a variable that names no kernel set or
    /// one this CPU lacks; [`Error::Embree`] when Embree cannot create a
    /// device (unsupported CPU, out of memory).
    pub fn new() -> Result<Device> {
        Isa::from_env()?.map_or_else(|| Self::with_config(""), Self::with_isa)
    }

    /// A device running Embree's `isa` kernel set, whatever the CPU's widest
    /// and the environment say. Maps traced with the same pinned set are the
    /// same on every x86-64 host that runs it (`docs/determinism.md`).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] when this CPU cannot run `isa`;
    /// [`Error::Embree`] when Embree cannot create a device.
    pub fn with_isa(isa: Isa) -> Result<Device> {
        Self::with_config(&format!("isa={isa}"))
    }

    /// [`Device::with_isa`] for `Some`, [`Device::new`] for `None`: the
    /// device of a setting that may pin a kernel set.
    ///
    /// # Errors
    /// As those two.
    pub fn pinned_or_default(pin: Option<Isa>) -> Result<Device> {
        pin.map_or_else(Self::new, Self::with_isa)
    }

    /// A device with an Embree configuration string, e.g. `"threads=2,verbose=1"`
    /// (see `rtcNewDevice(3)`). An `isa=` or `max_isa=` item must name a
    /// kernel set ([`Isa`]) that this CPU runs: Embree itself would run SSE2
    /// for an unknown name, and crash on a set the CPU lacks.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] when `config` contains a NUL byte or a bad
    /// kernel set; [`Error::Embree`] when Embree rejects the configuration or
    /// cannot create a device.
    pub fn with_config(config: &str) -> Result<Device> {
        let isa = kernel_set_of(config)?;
        let c_config = CString::new(config)
            .map_err(|_| Error::param("config", format!("contains a NUL byte: {config:?}")))?;
        // SAFETY: `c_config` is NUL-terminated and lives across the call.
        let raw = unsafe { sys::rtcNewDevice(c_config.as_ptr()) };
        let Some(raw) = NonNull::new(raw) else {
            // SAFETY: a null device asks for the error of the last failed
            // device creation on this thread.
            let code = unsafe { sys::rtcGetDeviceError(std::ptr::null_mut()) };
            return Err(Error::Embree {
                code,
                message: format!("rtcNewDevice({config:?}) returned null"),
            });
        };
        let errors = Box::<ErrorSlot>::default();
        let user = &*errors as *const ErrorSlot as *mut c_void;
        // SAFETY: `raw` is live; `user` points into a box that `DeviceInner`
        // owns and that outlives the registration (see `DeviceInner::drop`).
        unsafe { sys::rtcSetDeviceErrorFunction(raw.as_ptr(), Some(record_error), user) };
        Ok(Device {
            inner: Arc::new(DeviceInner {
                raw,
                errors,
                lock: Mutex::new(()),
                isa,
            }),
        })
    }

    /// The kernel set Embree runs on this device: the pinned one, else the
    /// CPU's widest (`None` off x86-64). Photon files record it.
    pub fn isa(&self) -> Option<Isa> {
        self.inner.isa
    }

    /// The version of the Embree library loaded at run time, `(major, minor, patch)`.
    pub fn version(&self) -> (u32, u32, u32) {
        self.inner.version()
    }

    /// Queries a device property (`RTC_DEVICE_PROPERTY_*` in `embree_sys`).
    ///
    /// # Errors
    /// [`Error::Embree`] when Embree does not know the property (or when an
    /// earlier error on this device had not been checked yet).
    pub fn property(&self, property: sys::RTCDeviceProperty) -> Result<isize> {
        let _guard = self.inner.lock();
        // SAFETY: the device is live; Embree validates `property` and reports
        // an unknown one through the error callback.
        let value = unsafe { sys::rtcGetDeviceProperty(self.inner.raw(), property) };
        self.inner.check().map(|()| value)
    }

    /// Returns, and clears, the first error Embree reported on this device
    /// since the last check.
    ///
    /// # Errors
    /// That error, as [`Error::Embree`].
    pub fn check(&self) -> Result<()> {
        self.inner.check()
    }

    /// The raw handle, for calls the wrapper does not cover. It stays valid
    /// while `self` (or any scene made from it) is alive; do not release it.
    pub fn raw(&self) -> sys::RTCDevice {
        self.inner.raw()
    }
}
