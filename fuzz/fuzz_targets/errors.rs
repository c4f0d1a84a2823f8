//! The error channel: `mf_status_str` for any integer, `mf_last_error_message` with any buffer
//! length after a failing call, `mf_version`, and `*_free(NULL)`.
#![no_main]

use libfuzzer_sys::fuzz_target;
use macrofacet_ffi::*;
use macrofacet_fuzz::build;
use macrofacet_fuzz::check;
use macrofacet_fuzz::input::Bytes;
use std::ffi::CStr;

fuzz_target!(|data: &[u8]| {
    let mut b = Bytes::new(data);
    // Any integer has a static description; the known codes have their own.
    let code = if b.bool() { b.u32() as i32 } else { b.choose(&[0, 7101, 7102, 7103, 7104, 7105, 7106, 7107, 7199, 7100, 7108, -1, i32::MIN]) };
    // SAFETY: mf_status_str returns a static NUL-terminated string.
    let text = unsafe { CStr::from_ptr(mf_status_str(code)) }.to_str().expect("UTF-8");
    let known = matches!(code, 0 | 7101..=7108 | 7199);
    assert_eq!(text == "unknown status", !known, "mf_status_str({code}) = {text}");
    // SAFETY: mf_version returns a static NUL-terminated string.
    let version = format!("{MF_VERSION_MAJOR}.{MF_VERSION_MINOR}.{MF_VERSION_PATCH}");
    assert_eq!(unsafe { CStr::from_ptr(mf_version()) }.to_str(), Ok(version.as_str()));

    // A failing call from the parameter parser, then the message read back with any buffer.
    let params = build::arbitrary_params(&mut b);
    let _ = build::medium(&params);
    let message = check::last_error();
    let len = b.below(message.len() + 8);
    let mut buf = vec![0xA5u8; len.max(1)];
    let mut out_len = usize::MAX;
    let with_len = b.bool();
    let out_len_ptr = if with_len { &mut out_len as *mut usize } else { std::ptr::null_mut() };
    let null_buf = len > 0 && b.u8() % 8 == 0;
    let buf_ptr = if null_buf || len == 0 && b.bool() { std::ptr::null_mut() } else { buf.as_mut_ptr().cast() };
    // SAFETY: buf holds at least len bytes (or is NULL, which the function must handle).
    let status = unsafe { mf_last_error_message(buf_ptr, len, out_len_ptr) };
    if null_buf {
        assert_eq!(status, mf_status::MF_ERROR_NULL_POINTER);
        return;
    }
    assert_eq!(status, mf_status::MF_OK);
    if with_len {
        assert_eq!(out_len, message.len(), "out_len");
    }
    if len > 0 {
        let n = message.len().min(len - 1);
        assert_eq!(&buf[..n], &message.as_bytes()[..n], "truncated message");
        assert_eq!(buf[n], 0, "NUL terminator");
        assert!(buf[n + 1..len].iter().all(|x| *x == 0xA5), "written past the terminator");
    }
    // The message survives a successful call.
    let _ = build::params_handle(&[]);
    assert_eq!(check::last_error(), message);
    // Releasing NULL is a no-op.
    unsafe {
        mf_params_free(std::ptr::null_mut());
        mf_medium_free(std::ptr::null_mut());
        mf_gpis_free(std::ptr::null_mut());
    }
});
