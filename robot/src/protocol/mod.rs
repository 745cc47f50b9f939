//! Bytes on the wire: the line protocol of the two microcontrollers (thesis App. A) and the SICK
//! LMS2xx telegrams ([`sick`]).
//!
//! A command is a letter, then non-negative decimal arguments (0..=65535) separated by one space,
//! then `\n`, at 9600 bps 8N1. Each command answers with its letter and `\n` at once; `l`, `t`
//! and `w` answer as the firmware code writes them (`report_status`, `bateries`,
//! `check_end_wait`). This module encodes the typed commands of
//! [`hardware`](crate::hardware) and parses the replies, so the twin's firmware emulation and a
//! real serial backend agree byte for byte.

pub mod base;
pub mod line;
pub mod pan_tilt;
pub mod sick;

/// Time to send `bytes` bytes over an asynchronous serial line at `baud` bits per second with one
/// start bit, eight data bits and one stop bit (8N1: ten bits per byte).
///
/// ```
/// use robot::protocol::serial_time;
/// // "l\n" at 9600 bps takes 2.083 ms.
/// assert_eq!(serial_time(2, 9600).as_nanos(), 2_083_333);
/// ```
pub fn serial_time(bytes: usize, baud: u32) -> core::time::Duration {
    if baud == 0 {
        return core::time::Duration::ZERO;
    }
    let nanos = (bytes as u128 * 10 * 1_000_000_000) / u128::from(baud);
    core::time::Duration::from_nanos(nanos as u64)
}

/// A `0`/`1` flag field of a reply.
pub(crate) fn parse_flag(field: &str) -> Option<bool> {
    match field {
        "0" => Some(false),
        "1" => Some(true),
        _ => None,
    }
}

/// The fields of a reply line `<letter>f1 f2 …\n`, or `None` without its letter or newline.
pub(crate) fn reply_fields(line: &str, letter: char) -> Option<Vec<&str>> {
    let body = line.strip_suffix('\n')?.strip_prefix(letter)?;
    Some(body.split(' ').collect())
}
