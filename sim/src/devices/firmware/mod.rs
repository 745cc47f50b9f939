//! Firmware of the robot's two microcontrollers — the base and the pan-tilt — ported from the
//! thesis's C code (App. A.3), and the boards that run it.

pub mod base;
pub mod board;
pub mod pan_tilt;

pub use base::{BaseFirmware, HBridge};
pub use board::{BaseBoard, Board, MainLoop};
pub use pan_tilt::PanTiltFirmware;

/// `limit_range` of both firmwares' `control.c`: a PWM duty moved by `error`, kept in 0..=255.
pub(crate) fn limit_range(pwm: u8, error: i32) -> u8 {
    (i32::from(pwm) + error).clamp(0, 255) as u8
}

/// Argument slots of both firmwares (`static unsigned short param[20]`).
pub(crate) const MAX_PARAMS: usize = 20;

/// `decode_command` of both firmwares' `main.c`: the letter, then decimal arguments split at
/// spaces and the newline into `param`. Non-digits are folded in as `c - '0'` like the C code
/// does; `\r` is skipped; slots past the C array are dropped. Returns the letter and the number
/// of arguments as the C code counts them.
pub(crate) fn decode_command(line: &[u8], param: &mut [u16; MAX_PARAMS]) -> (u8, i32) {
    let command = line.first().copied().unwrap_or(0);
    let mut num_params: usize = 0;
    param[0] = 0;
    let mut inicio_num = false;
    for &c in line.iter().skip(1) {
        match c {
            b'\r' => continue,
            b' ' | b'\n' => {
                // param[++num_params] = 0
                num_params += 1;
                if num_params < MAX_PARAMS {
                    param[num_params] = 0;
                }
            }
            _ => {
                inicio_num = true;
                if num_params < MAX_PARAMS {
                    let p = &mut param[num_params];
                    *p = p
                        .wrapping_mul(10)
                        .wrapping_add(u16::from(c).wrapping_sub(u16::from(b'0')));
                }
            }
        }
    }
    let mut n = num_params.min(MAX_PARAMS - 1) as i32;
    if !inicio_num {
        n -= 1;
    }
    (command, n)
}
