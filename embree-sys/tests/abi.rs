//! The Rust view of Embree's ABI agrees with the C compiler's and with the
//! library loaded at run time: a header/library mismatch (say Embree 4
//! headers with an Embree 3 `.so` on the library path) fails here rather
//! than as memory corruption in a ray query.

use adaptive_pm_embree_sys::*;

#[test]
fn rayhit_size_matches_the_c_compiler() {
    // SAFETY: the shim functions take no arguments and return a constant.
    let (c_single, c_packet8, c_packet) = unsafe {
        (
            apm_sizeof_rayhit(),
            apm_sizeof_rayhit8(),
            apm_sizeof_rayhit16(),
        )
    };
    assert_eq!(c_single, core::mem::size_of::<RTCRayHit>());
    assert_eq!(c_packet8, core::mem::size_of::<RTCRayHit8>());
    assert_eq!(core::mem::align_of::<RTCRayHit8>(), 32);
    assert_eq!(c_packet, core::mem::size_of::<RTCRayHit16>());
    assert_eq!(core::mem::align_of::<RTCRayHit16>(), 64);
}

#[test]
fn header_major_matches_cfg_and_device() {
    // SAFETY: a constant-returning shim function.
    let header_major = unsafe { apm_header_version_major() };
    assert_eq!(header_major, EMBREE_MAJOR);
    assert_eq!(header_major, RTC_VERSION_MAJOR);

    // SAFETY: a null config string asks for the default device; the handle
    // is checked for null and released exactly once.
    unsafe {
        let device = rtcNewDevice(core::ptr::null());
        assert!(!device.is_null(), "rtcNewDevice returned null");
        let lib_major = rtcGetDeviceProperty(device, RTC_DEVICE_PROPERTY_VERSION_MAJOR);
        rtcReleaseDevice(device);
        assert_eq!(lib_major, header_major as isize);
    }
}
