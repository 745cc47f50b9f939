//! The base microcontroller's firmware — `control.c`, `command.c`, `isr.c` and `main.c` of the
//! thesis's App. A.3.1 — ported line by line. The C names are kept so the two can be read side
//! by side; where the thesis's prose and this code disagree, this code is what the robot does.
//!
//! The port is driven the way the hardware drives the C code (the board's timing — when the main
//! loop is free, how long the UART takes — lives in [`super::board`]):
//!
//! - [`BaseFirmware::execute_line`] is the main loop's command dispatch for one received line
//!   (`decode_command`, `do_command`, `check_end_commands`);
//! - [`BaseFirmware::rti_interrupt`] is the 1.024 ms real-time interrupt (`ISR_RealTimeInt`);
//! - [`BaseFirmware::check_rtf`] is the main loop's work after an interrupt (`get_vel`,
//!   `speed_control`, `ac_control`, `sonar_demon`, then `check_end_commands`);
//! - [`BaseFirmware::bridges`] are the H-bridge inputs it drives (direction, brake, PWM duty),
//!   and [`BaseFirmware::take_output`] the bytes it has written to the serial port.
//!
//! Behaviours of the code worth knowing (all reproduced):
//! - the acceleration timer reloads with `Tc` and acts when it has counted down, so the desired
//!   speed changes every `Tc + 1` ticks;
//! - the proportional term divides by 100 with truncation: a speed error of ±1 count per tick
//!   changes nothing;
//! - wheel counters stop counting as soon as the motors are switched off, so the wheels' coast
//!   after the brake is never reported;
//! - `v` does not reset the braking point: the stale `clicks_break` makes `check_stop_motors`
//!   start braking at once, and the desired speeds ramp down to zero;
//! - `w` honours its flags only when all three are given; with fewer arguments it just waits;
//! - argument slots not written by the current command keep the values of earlier commands.

use super::{MAX_PARAMS, limit_range};
use std::fmt::Write as _;

/// Greatest number of sonars in a sequence (`MAX_SONARS`).
pub const MAX_SONARS: usize = 16;
/// Longest command line the receive buffer holds (`g_command_line[256]`).
const LINE_CAPACITY: usize = 255;

/// The inputs of one LMD18200 H-bridge as the firmware sets them.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct HBridge {
    /// Logical direction: the wheel is driven forward (pins mirrored on the right side).
    pub forward: bool,
    /// Brake pin: with PWM high the bridge shorts the motor.
    pub brake: bool,
    /// PWM duty, 0..=255.
    pub pwm: u8,
}

impl HBridge {
    /// `m_*_stop`: direction pin high, brake on, PWM 255 (the motor is shorted).
    pub(crate) const STOPPED: HBridge = HBridge {
        forward: true,
        brake: true,
        pwm: 255,
    };
}

/// The state of the base microcontroller.
#[derive(Clone, Debug)]
pub struct BaseFirmware {
    // ---- control.c ----
    g_left_vel: u8,
    g_right_vel: u8,
    des_left_vel_clicks: i16,
    des_right_vel_clicks: i16,
    des_bias_clicks: i16,
    max_left_vel_clicks: i16,
    max_right_vel_clicks: i16,
    max_bias_clicks: i16,
    integral: i16,
    k_integral: i32,
    k_pro: i32,
    edo_left_motor: bool,
    edo_right_motor: bool,
    sonar_wait: i16,
    k_vel_ini: i16,
    k_vel_end: i16,
    k_ms_inc: i16,
    clicks_stop: u32,
    clicks_break: u32,
    total_left_clicks: u32,
    total_right_clicks: u32,
    acelerando: bool,
    frenando: bool,
    timer_ac: i16,
    left: HBridge,
    right: HBridge,
    beep: bool,
    // sonar (control.c)
    sonar_sec: [u8; MAX_SONARS],
    sonar: [u16; MAX_SONARS],
    sonar_num: usize,
    sonar_edo: bool,
    sonar_index: usize,
    sonar_waiting_init: bool,
    sonar_waiting_echo: u16,
    sonar_waiting_relax: u16,
    sonar_ready2fire: bool,
    sonar_time_start: u16,
    sonar_time_end: u16,
    sonar_cycles: u16,
    sonar_max_time_echo: u16,
    sonar_time_relax: u16,
    sonar_fired: Option<u8>,
    sonar_stored: Option<usize>,
    // ---- command.c ----
    edo_wait: u16,
    wait_for_left_motor: bool,
    wait_for_right_motor: bool,
    wait_for_sonar: bool,
    // ---- isr.c ----
    g_timer: u16,
    g_ad: [u16; 4],
    // ---- main.c / serial.c ----
    param: [u16; MAX_PARAMS],
    line: Vec<u8>,
    tx: Vec<u8>,
}

impl Default for BaseFirmware {
    fn default() -> Self {
        Self::power_on()
    }
}

impl BaseFirmware {
    /// The microcontroller after reset: `main` up to the greeting, and `init_control`.
    pub fn power_on() -> Self {
        let mut fw = BaseFirmware {
            g_left_vel: 0,
            g_right_vel: 0,
            des_left_vel_clicks: 0,
            des_right_vel_clicks: 0,
            des_bias_clicks: 0,
            max_left_vel_clicks: 0,
            max_right_vel_clicks: 0,
            max_bias_clicks: 0,
            integral: 0,
            k_integral: 1,
            k_pro: 50,
            edo_left_motor: false,
            edo_right_motor: false,
            sonar_wait: 0,
            k_vel_ini: 5,
            k_vel_end: 30,
            k_ms_inc: 50,
            clicks_stop: 0,
            clicks_break: 0,
            total_left_clicks: 0,
            total_right_clicks: 0,
            acelerando: false,
            frenando: false,
            timer_ac: 0,
            left: HBridge::STOPPED,
            right: HBridge::STOPPED,
            beep: false,
            sonar_sec: core::array::from_fn(|i| i as u8),
            sonar: [u16::MAX; MAX_SONARS],
            sonar_num: MAX_SONARS,
            sonar_edo: false,
            sonar_index: 0,
            sonar_waiting_init: false,
            sonar_waiting_echo: 0,
            sonar_waiting_relax: 0,
            sonar_ready2fire: false,
            sonar_time_start: 0,
            sonar_time_end: 0,
            sonar_cycles: 0,
            sonar_max_time_echo: 50,
            sonar_time_relax: 20,
            sonar_fired: None,
            sonar_stored: None,
            edo_wait: 0,
            wait_for_left_motor: false,
            wait_for_right_motor: false,
            wait_for_sonar: false,
            g_timer: 0,
            g_ad: [0; 4],
            param: [0; MAX_PARAMS],
            line: Vec::with_capacity(LINE_CAPACITY),
            tx: Vec::new(),
        };
        fw.puts("Robot ROCA-MOBILE-2 v1.0 listo\n");
        // init_control: max_* = 0; set_velocity() — the motors start braked.
        fw.set_velocity();
        fw
    }

    // ------------------------------------------------------------------ interface to the twin

    /// Decodes and executes one received command line (up to and including its `\n`), as the
    /// main loop does when `g_command_pending` is set. A line longer than the C buffer is cut
    /// at 255 bytes (the C code would overrun).
    pub fn execute_line(&mut self, line: &[u8]) {
        let line = &line[..line.len().min(LINE_CAPACITY)];
        let (command, num_params) = super::decode_command(line, &mut self.param);
        self.do_command(command, num_params);
    }

    /// Feeds bytes as the receive interrupt would, executing each line as soon as it is
    /// complete (a main loop that is never busy). Convenient for tests.
    pub fn receive(&mut self, bytes: &[u8]) {
        for &c in bytes {
            self.line.push(c);
            if c == b'\n' {
                let line = std::mem::take(&mut self.line);
                self.execute_line(&line);
            }
        }
    }

    /// `ISR_RealTimeInt`: every 1.024 ms, whatever the main loop is doing. `adc` holds the
    /// battery channels AN2..AN5 (10-bit counts).
    pub fn rti_interrupt(&mut self, adc: [u16; 4]) {
        if self.g_timer != 0 {
            self.g_timer -= 1;
        }
        self.g_ad = adc;
    }

    /// `get_vel`: the main loop latches the 8-bit pulse accumulators, which counted
    /// `left_edges` and `right_edges` since they were last latched (they saturate at 255,
    /// `PACMX`).
    pub fn latch_encoders(&mut self, left_edges: u32, right_edges: u32) {
        self.g_left_vel = left_edges.min(255) as u8;
        self.g_right_vel = right_edges.min(255) as u8;
    }

    /// `check_rtf` after `get_vel`, and `check_end_commands`: the main loop's work after a
    /// real-time interrupt.
    pub fn check_rtf(&mut self) {
        self.speed_control();
        self.ac_control();
        self.sonar_demon();
        self.check_end_commands();
    }

    /// An interrupt followed at once by the main loop's work (a main loop that is never busy).
    pub fn rti_tick(&mut self, left_edges: u32, right_edges: u32, adc: [u16; 4]) {
        self.rti_interrupt(adc);
        self.latch_encoders(left_edges, right_edges);
        self.check_rtf();
    }

    /// The H-bridge inputs (left, right).
    pub fn bridges(&self) -> (HBridge, HBridge) {
        (self.left, self.right)
    }

    /// Takes the bytes written to the serial port since the last call.
    pub fn take_output(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.tx)
    }

    /// Whether bytes are waiting to be taken.
    pub fn has_output(&self) -> bool {
        !self.tx.is_empty()
    }

    /// The transducer fired during the last tick, if any (the multiplexer address).
    pub fn take_sonar_fired(&mut self) -> Option<u8> {
        self.sonar_fired.take()
    }

    /// The position of the firing sequence whose reading was stored during the last tick.
    pub fn take_sonar_stored(&mut self) -> Option<usize> {
        self.sonar_stored.take()
    }

    /// Ticks the echo line is listened to after a shot: the `waiting_init` tick and `Te`.
    pub fn sonar_window_ticks(&self) -> u32 {
        u32::from(self.sonar_max_time_echo) + 1
    }

    /// The firing sequence (`S`).
    pub fn sonar_sequence(&self) -> &[u8] {
        &self.sonar_sec[..self.sonar_num]
    }

    /// Whether the sonar ring is firing (`sonar_edo`).
    pub fn sonar_firing(&self) -> bool {
        self.sonar_edo
    }

    /// The echo interrupt (`ISR_SonarEcho`): the echo line rose `units` timer counts
    /// (5.33 µs each) after the last shot. The port counts the timer from the shot, so
    /// `sonar_time_end - sonar_time_start` is `units` as on the robot.
    pub fn sonar_echo(&mut self, units: u16) {
        self.sonar_time_end = units;
    }

    /// Desired speeds of the ramp, counts per tick (left, right).
    pub fn desired_speeds(&self) -> (i16, i16) {
        (self.des_left_vel_clicks, self.des_right_vel_clicks)
    }

    /// Counts accumulated since the last motion command (left, right).
    pub fn totals(&self) -> (u32, u32) {
        (self.total_left_clicks, self.total_right_clicks)
    }

    /// Whether each drive motor is on (left, right).
    pub fn motors_on(&self) -> (bool, bool) {
        (self.edo_left_motor, self.edo_right_motor)
    }

    /// Whether the buzzer sounds.
    pub fn buzzer(&self) -> bool {
        self.beep
    }

    // ------------------------------------------------------------------ serial.c

    fn puts(&mut self, s: &str) {
        self.tx.extend_from_slice(s.as_bytes());
    }

    fn putchar(&mut self, c: u8) {
        self.tx.push(c);
    }

    /// `ser0_putushort`: decimal digits without padding.
    fn putushort(&mut self, x: u16) {
        let mut s = String::new();
        let _ = write!(s, "{x}");
        self.puts(&s);
    }

    // ------------------------------------------------------------------ command.c

    fn do_command(&mut self, command: u8, num_params: i32) {
        match command {
            b'w' => self.wait(num_params),
            b'q' => self.query(),
            b'v' => self.set_vel(num_params),
            b'p' => self.stop(),
            b't' => self.bateries(),
            b'k' => self.set_ac(),
            b'a' => self.forward(num_params),
            b'r' => self.backward(num_params),
            b'i' => self.turn_left(num_params),
            b'd' => self.turn_right(num_params),
            b's' => self.sonar_cmd(num_params),
            b'S' => self.sonar_def_sec(num_params),
            b'l' => self.report_status(),
            b'z' => self.beep_cmd(),
            b'*' => self.puts("*\n"),
            b'?' => self.print_help(),
            _ => {}
        }
        self.check_end_commands();
    }

    fn wait(&mut self, num_params: i32) {
        self.g_timer = self.param[0];
        if num_params == 4 {
            self.wait_for_left_motor = self.param[1] != 0;
            self.wait_for_right_motor = self.param[2] != 0;
            self.wait_for_sonar = self.param[3] != 0;
        } else {
            self.wait_for_left_motor = false;
            self.wait_for_right_motor = false;
            self.wait_for_sonar = false;
        }
        self.edo_wait = 1;
    }

    fn check_end_wait(&mut self) {
        if self.edo_wait != 0 {
            self.edo_wait = 0;
            if self.wait_for_left_motor && self.edo_left_motor {
                self.edo_wait = 1;
            }
            if self.wait_for_right_motor && self.edo_right_motor {
                self.edo_wait = 1;
            }
            if self.wait_for_sonar && self.sonar_wait != 0 {
                self.edo_wait = 1;
            }
            if (!self.wait_for_left_motor && !self.wait_for_right_motor && !self.wait_for_sonar)
                || self.edo_wait != 0
            {
                self.edo_wait = self.g_timer;
            }
            if self.edo_wait == 0 {
                self.puts("w\n");
            }
        }
    }

    fn query(&mut self) {
        self.puts("sonar_wait=");
        self.putushort(self.sonar_wait as u16);
        self.putchar(b'\n');
    }

    /// `bateries` with `ROBOT2` defined: the calibration factors are integer divisions.
    fn bateries(&mut self) {
        let [ad2, ad3, ad4, ad5] = self.g_ad.map(u32::from);
        let bat12 = (ad2 * (127_200 / 639)) / 10;
        let bat24 = (ad3 * (259_000 / 691)) / 10;
        let bat12m = (ad4 * (130_100 / 691)) / 10;
        let bat24m = (ad5 * (261_000 / 696)) / 10;
        self.putchar(b't');
        self.putushort(bat12 as u16);
        self.putchar(b' ');
        self.putushort(bat24 as u16);
        self.putchar(b' ');
        self.putushort(bat12m as u16);
        self.putchar(b' ');
        self.putushort(bat24m as u16);
        self.putchar(b'\n');
    }

    fn check_end_commands(&mut self) {
        self.check_end_wait();
        self.check_stop_motors();
    }

    fn print_help(&mut self) {
        for line in HELP {
            self.puts(line);
        }
    }

    // ------------------------------------------------------------------ control.c: motion

    fn set_velocity(&mut self) {
        if self.max_left_vel_clicks == 0
            && self.max_right_vel_clicks == 0
            && self.max_bias_clicks == 0
        {
            self.left = HBridge::STOPPED;
            self.right = HBridge::STOPPED;
            self.edo_left_motor = false;
            self.edo_right_motor = false;
            self.acelerando = false;
            self.frenando = false;
            return;
        }
        self.left.pwm = 0;
        self.right.pwm = 0;
        self.edo_left_motor = true;
        self.edo_right_motor = true;
        self.integral = 0;
        self.des_left_vel_clicks = self.max_left_vel_clicks.wrapping_abs();
        self.des_right_vel_clicks = self.max_right_vel_clicks.wrapping_abs();
        self.des_bias_clicks = self.max_bias_clicks;
        // m_izq_forward / m_izq_backward and the right-hand twins: brake released.
        self.left.forward = self.max_left_vel_clicks > 0;
        self.left.brake = false;
        self.right.forward = self.max_right_vel_clicks > 0;
        self.right.brake = false;
    }

    fn m_stop(&mut self) {
        self.edo_left_motor = false;
        self.edo_right_motor = false;
        self.max_left_vel_clicks = 0;
        self.max_right_vel_clicks = 0;
        self.max_bias_clicks = 0;
        self.set_velocity();
    }

    fn stop(&mut self) {
        self.puts("p\n");
        self.m_stop();
    }

    fn set_vel(&mut self, num_params: i32) {
        self.puts("v\n");
        if num_params >= 2 {
            self.max_left_vel_clicks = self.param[0].wrapping_sub(100) as i16;
            self.max_right_vel_clicks = self.param[1].wrapping_sub(100) as i16;
        }
        if num_params == 3 {
            self.max_bias_clicks = self.param[2].wrapping_sub(100) as i16;
        } else {
            self.max_bias_clicks = 0;
        }
        self.set_velocity();
        self.clicks_stop = 0;
        self.acelerando = false;
        self.frenando = false;
    }

    fn set_ac(&mut self) {
        self.puts("k\n");
        self.k_vel_ini = self.param[0] as i16;
        self.k_vel_end = self.param[1] as i16;
        self.k_ms_inc = self.param[2] as i16;
    }

    fn set_params(&mut self, num_params: i32) {
        self.clicks_stop = if num_params == 0 {
            0
        } else {
            u32::from(self.param[0]) * 100
        };
        self.total_left_clicks = 0;
        self.total_right_clicks = 0;
        self.clicks_break = self.clicks_stop / 2;
        self.timer_ac = self.k_ms_inc;
        self.max_bias_clicks = 0;
        self.acelerando = true;
        self.frenando = false;
    }

    fn forward(&mut self, num_params: i32) {
        self.puts("a\n");
        self.set_params(num_params);
        self.max_left_vel_clicks = self.k_vel_ini;
        self.max_right_vel_clicks = self.k_vel_ini;
        self.set_velocity();
    }

    fn backward(&mut self, num_params: i32) {
        self.puts("r\n");
        self.set_params(num_params);
        self.max_left_vel_clicks = self.k_vel_ini.wrapping_neg();
        self.max_right_vel_clicks = self.k_vel_ini.wrapping_neg();
        self.set_velocity();
    }

    fn turn_left(&mut self, num_params: i32) {
        self.puts("i\n");
        self.set_params(num_params);
        self.max_left_vel_clicks = self.k_vel_ini.wrapping_neg();
        self.max_right_vel_clicks = self.k_vel_ini;
        self.set_velocity();
    }

    fn turn_right(&mut self, num_params: i32) {
        self.puts("d\n");
        self.set_params(num_params);
        self.max_left_vel_clicks = self.k_vel_ini;
        self.max_right_vel_clicks = self.k_vel_ini.wrapping_neg();
        self.set_velocity();
    }

    fn speed_control(&mut self) {
        if !self.edo_left_motor && !self.edo_right_motor {
            return;
        }
        let left_vel = i32::from(self.g_left_vel);
        let right_vel = i32::from(self.g_right_vel);
        self.total_left_clicks = self.total_left_clicks.wrapping_add(left_vel as u32);
        self.total_right_clicks = self.total_right_clicks.wrapping_add(right_vel as u32);
        // integral is a C `short`: the sum wraps at 16 bits.
        self.integral = (i32::from(self.integral) + left_vel + i32::from(self.des_bias_clicks)
            - right_vel) as i16;
        let integral_error = self.k_integral * i32::from(self.integral) / 100;
        let left_error =
            self.k_pro * (i32::from(self.des_left_vel_clicks) - left_vel - integral_error) / 100;
        let right_error =
            self.k_pro * (i32::from(self.des_right_vel_clicks) - right_vel + integral_error) / 100;
        self.left.pwm = limit_range(self.left.pwm, left_error);
        self.right.pwm = limit_range(self.right.pwm, right_error);
    }

    fn ac_control(&mut self) {
        if self.timer_ac != 0 {
            self.timer_ac -= 1;
            return;
        }
        if self.acelerando {
            if i32::from(self.g_left_vel) + 3 >= i32::from(self.k_vel_end) {
                // reach the max velocity
                self.clicks_break = self.clicks_stop.wrapping_sub(self.total_left_clicks);
                self.acelerando = false;
            }
            if self.des_left_vel_clicks < self.k_vel_end {
                self.des_left_vel_clicks += 1;
            }
            self.des_right_vel_clicks = self.des_right_vel_clicks.wrapping_add(1);
        }
        if self.frenando && self.des_left_vel_clicks != 0 {
            self.des_left_vel_clicks -= 1;
            self.des_right_vel_clicks = self.des_right_vel_clicks.wrapping_sub(1);
        }
        self.timer_ac = self.k_ms_inc;
    }

    fn check_stop_motors(&mut self) {
        if self.clicks_stop != 0
            && self.total_left_clicks >= self.clicks_stop
            && self.total_right_clicks >= self.clicks_stop
        {
            self.m_stop();
        }
        if self.edo_left_motor && !self.frenando && self.total_left_clicks >= self.clicks_break {
            self.acelerando = false;
            self.frenando = true;
        }
    }

    fn report_clicks(&mut self, total_clicks: u32) {
        let turns = total_clicks / 100;
        let clicks = total_clicks - turns * 100;
        self.putushort(turns as u16);
        self.putchar(b'.');
        if clicks < 10 {
            self.putchar(b'0');
        }
        self.putushort(clicks as u16);
    }

    fn report_status(&mut self) {
        self.putchar(b'l');
        self.report_clicks(self.total_left_clicks);
        self.putchar(b' ');
        self.report_clicks(self.total_right_clicks);
        self.putchar(b' ');
        self.putushort(u16::from(self.edo_left_motor));
        self.putchar(b' ');
        self.putushort(u16::from(self.edo_right_motor));
        self.putchar(b' ');
        self.putushort(u16::from(self.sonar_edo));
        self.putchar(b'\n');
    }

    fn beep_cmd(&mut self) {
        self.puts("z\n");
        self.beep = self.param[0] != 0;
    }

    // ------------------------------------------------------------------ control.c: sonar ring

    fn sonar_report(&mut self) {
        for i in 0..self.sonar_num {
            self.putushort(self.sonar[i]);
            self.putchar(b'\n');
        }
        self.sonar_wait = self.sonar_num as i16 + 1;
    }

    fn sonar_stop(&mut self) {
        self.sonar_edo = false;
        self.putchar(b'\n');
    }

    fn sonar_start(&mut self) {
        self.sonar_cycles = 0;
        self.sonar_index = 0;
        self.sonar_waiting_echo = 0;
        self.sonar_waiting_relax = 0;
        self.sonar[..self.sonar_num].fill(u16::MAX);
        self.sonar_ready2fire = true;
        self.sonar_edo = true;
        self.sonar_wait = self.sonar_num as i16;
        self.putchar(b'\n');
    }

    fn sonar_def_param(&mut self) {
        self.sonar_max_time_echo = self.param[1];
        self.sonar_time_relax = self.param[2];
        self.putchar(b'\n');
    }

    fn sonar_report_cycles(&mut self) {
        self.putushort(self.sonar_cycles);
        self.putchar(b'\n');
    }

    fn sonar_cmd(&mut self, num_params: i32) {
        self.putchar(b's');
        if num_params == 0 {
            self.sonar_report();
        } else if self.param[0] == 0 {
            self.sonar_stop();
        } else if self.param[0] == 1 {
            self.sonar_start();
        } else if self.param[0] == 2 {
            self.sonar_def_param();
        } else {
            self.sonar_report_cycles();
        }
    }

    /// `sonar_def_sec`. A sequence longer than 16 (or empty) would overrun the C arrays; the
    /// port keeps between 1 and 16 entries.
    fn sonar_def_sec(&mut self, num_params: i32) {
        self.puts("S\n");
        let n = num_params.clamp(1, MAX_SONARS as i32) as usize;
        self.sonar_num = n;
        for i in 0..n {
            self.sonar_sec[i] = self.param[i] as u8;
        }
    }

    fn sonar_demon(&mut self) {
        if !self.sonar_edo {
            return;
        }
        if self.sonar_ready2fire {
            let active = self.sonar_sec[self.sonar_index] & 0x0f;
            self.sonar_fired = Some(active);
            self.sonar_time_start = 0;
            self.sonar_time_end = 0;
            self.sonar_ready2fire = false;
            self.sonar_waiting_init = true;
        } else if self.sonar_waiting_init {
            self.sonar_waiting_init = false;
            self.sonar_waiting_echo = self.sonar_max_time_echo;
        } else if self.sonar_waiting_echo != 0 {
            self.sonar_waiting_echo -= 1;
            if self.sonar_waiting_echo == 0 {
                let time = self.sonar_time_end.wrapping_sub(self.sonar_time_start);
                self.sonar[self.sonar_index] = if time != 0 { time } else { u16::MAX };
                self.sonar_stored = Some(self.sonar_index);
                self.sonar_waiting_relax = self.sonar_time_relax;
            }
        } else if self.sonar_waiting_relax != 0 {
            self.sonar_waiting_relax -= 1;
        } else {
            self.sonar_ready2fire = true;
            self.sonar_index += 1;
            if self.sonar_index == self.sonar_num {
                self.sonar_index = 0;
                self.sonar_cycles = self.sonar_cycles.wrapping_add(1);
            }
            if self.sonar_wait != 0 {
                self.sonar_wait -= 1;
            }
        }
    }
}

/// `limit_range`: add the error to the duty and clamp to 0..=255.
/// `print_help`, as in App. A.
const HELP: [&str; 20] = [
    "Comandos disponibles:\n\n",
    "? Imprime este mensaje de ayuda\n",
    "* Regresa un asterisco\n",
    "a<pi> Avanza pi unidades\n",
    "d<pi> Gira a la derecha pi unidades\n",
    "i<pi> Gira a la izquierda pi unidades\n",
    "k<pi> <pf> <ms> Define la aceleracion de los motores de las ruedas\n",
    "l Reporta el estado del robot\n",
    "p Paro de emergencia de los motores de las ruedas\n",
    "r<pi> Retrocede pi unidades\n",
    "s0 Apaga el anillo de sonares\n",
    "s1 Inicia los disparos del anillo de sonares\n",
    "s2 <te> <tr> Fija parametros de disparo del anillo de sonares\n",
    "s3 Regresa el numero de ciclos que han disparado los sonares\n",
    "S <s0> <s1> ... Define la secuencia de disparo del anillo de sonares\n",
    "t Regresa el voltaje de las baterias en milivolts\n",
    "w Espera por paro de motores de las ruedas y el sonar\n",
    "z0 Desactiva el zumbador al frente del robot\n",
    "z1 Activa el zumbador al frente del robot\n",
    "",
];

#[cfg(test)]
mod tests {
    use super::*;

    fn booted() -> BaseFirmware {
        let mut fw = BaseFirmware::power_on();
        fw.take_output();
        fw
    }

    fn reply(fw: &mut BaseFirmware, line: &str) -> String {
        fw.receive(line.as_bytes());
        String::from_utf8(fw.take_output()).unwrap()
    }

    #[test]
    fn greets_and_starts_braked() {
        let mut fw = BaseFirmware::power_on();
        assert_eq!(fw.take_output(), b"Robot ROCA-MOBILE-2 v1.0 listo\n");
        assert_eq!(fw.bridges().0, HBridge::STOPPED);
        assert_eq!(fw.motors_on(), (false, false));
    }

    #[test]
    fn every_command_answers_as_the_code_writes() {
        let mut fw = booted();
        assert_eq!(reply(&mut fw, "a10\n"), "a\n");
        assert_eq!(reply(&mut fw, "p\n"), "p\n");
        assert_eq!(
            reply(&mut fw, "r10\n"),
            "r\n",
            "the prose says `c`; the code answers `r`"
        );
        assert_eq!(reply(&mut fw, "k5 30 50\n"), "k\n");
        assert_eq!(reply(&mut fw, "z1\n"), "z\n");
        assert!(fw.buzzer());
        assert_eq!(reply(&mut fw, "*\n"), "*\n");
        assert_eq!(reply(&mut fw, "q\n"), "sonar_wait=0\n");
        assert_eq!(reply(&mut fw, "S15 0 1\n"), "S\n");
        assert_eq!(reply(&mut fw, "s\n"), "s65535\n65535\n65535\n");
        assert_eq!(reply(&mut fw, "x\n"), "", "unknown letters are ignored");
        assert!(reply(&mut fw, "?\n").starts_with("Comandos disponibles:"));
    }

    #[test]
    fn status_prints_turns_and_hundredths() {
        let mut fw = booted();
        fw.receive(b"a10\n");
        fw.take_output();
        for _ in 0..3 {
            fw.rti_tick(7, 3, [0; 4]);
        }
        assert_eq!(reply(&mut fw, "l\n"), "l0.21 0.09 1 1 0\n");
    }

    #[test]
    fn decode_folds_garbage_like_c_and_keeps_stale_slots() {
        let mut fw = booted();
        // "k5\n": param[1] is zeroed by the newline, param[2] keeps a stale value.
        fw.receive(b"k7 8 9\n");
        fw.receive(b"k5\n");
        assert_eq!((fw.k_vel_ini, fw.k_vel_end, fw.k_ms_inc), (5, 0, 9));
        // '\r' is skipped; a letter folds in as c - '0'.
        let (cmd, n) = crate::devices::firmware::decode_command(b"a1\r0\n", &mut fw.param);
        assert_eq!((cmd, n, fw.param[0]), (b'a', 1, 10));
        let (_, _) = crate::devices::firmware::decode_command(b"a1x\n", &mut fw.param);
        assert_eq!(fw.param[0], 10 + (u16::from(b'x') - u16::from(b'0')));
    }

    #[test]
    fn wait_with_three_arguments_ignores_its_flags() {
        let mut fw = booted();
        fw.receive(b"a100\n");
        fw.take_output();
        // The thesis's own example `w10000 1 1` has three arguments: a plain 10 s wait.
        assert_eq!(reply(&mut fw, "w3 1 1\n"), "");
        fw.rti_tick(5, 5, [0; 4]);
        fw.rti_tick(5, 5, [0; 4]);
        assert_eq!(String::from_utf8(fw.take_output()).unwrap(), "");
        fw.rti_tick(5, 5, [0; 4]);
        assert_eq!(String::from_utf8(fw.take_output()).unwrap(), "w\n");
        assert_eq!(
            fw.motors_on(),
            (true, true),
            "the motors were still running"
        );
    }

    #[test]
    fn wait_for_idle_motors_answers_at_once_when_idle() {
        let mut fw = booted();
        assert_eq!(reply(&mut fw, "w1000 1 1 0\n"), "w\n");
    }

    #[test]
    fn integral_wraps_like_a_c_short() {
        let mut fw = booted();
        fw.receive(b"v190 110\n");
        fw.integral = i16::MAX - 10;
        fw.rti_tick(90, 0, [0; 4]);
        assert!(fw.integral < 0, "{}", fw.integral);
    }
}
