//! Helpers shared by the C ABI's test files.

use macrofacet_ffi::*;

/// The calling thread's last error message (`mf_last_error_message`).
pub fn last_error() -> String {
    let mut buf = [0u8; 1024];
    let mut len = 0usize;
    assert_eq!(unsafe { mf_last_error_message(buf.as_mut_ptr().cast(), buf.len(), &mut len) }, mf_status::MF_OK);
    String::from_utf8_lossy(&buf[..len.min(buf.len() - 1)]).into_owned()
}
