//! The pan-tilt microcontroller's firmware — `control.c`, `command.c`, `isr.c` and `main.c` of the
//! thesis's App. A.3.2 — ported with the C names kept. Where the prose (App. A.2.2) and this code
//! disagree, this code is what the pan-tilt does:
//!
//! - positions are counted by the motors' **index pulses**, one per rotor turn, in the index
//!   interrupts (`ISR_MGiroI`, `ISR_MElevI`); a pulse counts only after 250 channel-B "clicks"
//!   (`OFFSET`) since the last one, so a motor hovering on its index does not count it twice; a
//!   move stops at the index that completes it;
//! - `g c` and `e c` move to absolute positions (pan clamped to `MAX_ABS_GIRO` = 248 on the
//!   thesis's robot, tilt to 100); `k` and `K` set the ramps; `l` answers nine fields, `l abs_giro
//!   g_giro_clicks abs_elev g_elev_clicks TopeIzq TopeDer TopeInf Eg Ee`, not the prose's
//!   `l Cg Ce Eg Ee`; `w ms Fg Fe` waits, `q` prints a debug array, `*` echoes;
//! - **there is no `p`**: `do_command` has no case for it, so a stop request gets no answer;
//! - `w ms 1 1` (the prose's example) always waits its full time: the condition in
//!   `check_end_wait` is `!(Fg && !Fe) || edo_wait`, which only lets "wait for the pan" end early;
//! - at power-up the main loop homes the unit (`init_secuence`): pan right onto its limit switch,
//!   back off it slowly, on to the next index (pan position 0); then the tilt down onto its switch,
//!   up off it, on to the next index (tilt position 0); it says so on the serial line (`DEBUG` is
//!   defined) and ends with `Listo`;
//! - the limit-switch interrupts fire on the switch being pressed (falling edge, `TCTL3`) and stop
//!   the pan when it moves towards that switch; the tilt's lower switch is polled.

use super::base::HBridge;
use super::board::MainLoop;
use super::{MAX_PARAMS, limit_range};
use std::fmt::Write as _;

/// `OFFSET`: channel-B clicks required between two counted index pulses.
const OFFSET: i32 = 250;
/// `MAX_ABS_GIRO` for `ROBOT1`, the pan-tilt on the thesis's robot.
pub const MAX_ABS_GIRO: u16 = 248;
/// `MAX_ABS_ELEV`.
pub const MAX_ABS_ELEV: u16 = 100;
const LINE_CAPACITY: usize = 255;

/// The steps of the power-up homing (`enum STEP_INIT`).
#[derive(Copy, Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Step {
    GiroDerStart,
    GiroDerEnd,
    GiroIzqStart,
    GiroIzqEnd,
    Giro1IzqStart,
    Giro1IzqEnd,
    ElevAbajoStart,
    ElevAbajoEnd,
    ElevArribaStart,
    ElevArribaEnd,
    Elev1ArribaStart,
    Elev1ArribaEnd,
    Ready,
    Done,
}

impl Step {
    fn next(self) -> Step {
        use Step::*;
        match self {
            GiroDerStart => GiroDerEnd,
            GiroDerEnd => GiroIzqStart,
            GiroIzqStart => GiroIzqEnd,
            GiroIzqEnd => Giro1IzqStart,
            Giro1IzqStart => Giro1IzqEnd,
            Giro1IzqEnd => ElevAbajoStart,
            ElevAbajoStart => ElevAbajoEnd,
            ElevAbajoEnd => ElevArribaStart,
            ElevArribaStart => ElevArribaEnd,
            ElevArribaEnd => Elev1ArribaStart,
            Elev1ArribaStart => Elev1ArribaEnd,
            Elev1ArribaEnd => Ready,
            Ready | Done => Done,
        }
    }
}

/// One axis of the unit: the state `control.c` and `isr.c` keep per motor (`*_giro` for pan,
/// `*_elev` for tilt).
#[derive(Clone, Debug)]
struct Axis {
    dir: bool,
    abs: i16,
    pos_control: bool,
    des_vel_clicks: i16,
    max_vel_clicks: i16,
    bridge: HBridge,
    k_pro: i32,
    edo_motor: bool,
    k_vel_ini: i16,
    k_vel_end: i16,
    k_ms_inc: i16,
    clicks_stop: u32,
    clicks_break: u32,
    total_clicks: u32,
    turns_stop: u16,
    acelerando: bool,
    frenando: bool,
    timer_ac: i16,
    g_vel: u8,
    g_index: u16,
    g_clicks: i16,
}

impl Axis {
    fn power_on() -> Self {
        Axis {
            dir: false,
            abs: 0,
            pos_control: false,
            des_vel_clicks: 0,
            max_vel_clicks: 0,
            bridge: HBridge::STOPPED,
            k_pro: 100,
            edo_motor: false,
            k_vel_ini: 3,
            k_vel_end: 50,
            k_ms_inc: 30,
            clicks_stop: 0,
            clicks_break: 0,
            total_clicks: 0,
            turns_stop: 0,
            acelerando: false,
            frenando: false,
            timer_ac: 0,
            g_vel: 0,
            g_index: 0,
            g_clicks: 0,
        }
    }

    /// `m_giro_stop` / `m_elev_stop`.
    fn motor_stop(&mut self) {
        self.bridge = HBridge::STOPPED;
        self.edo_motor = false;
        self.acelerando = false;
        self.frenando = false;
    }

    /// `set_velocity_giro` / `set_velocity_elev` (positive: pan left, tilt up).
    fn set_velocity(&mut self) {
        if self.max_vel_clicks == 0 {
            self.motor_stop();
            return;
        }
        self.bridge = HBridge {
            forward: self.max_vel_clicks > 0,
            brake: false,
            pwm: 0,
        };
        self.edo_motor = true;
        self.pos_control = false;
        self.des_vel_clicks = self.max_vel_clicks.wrapping_abs();
    }

    /// `m_stop_giro` / `m_stop_elev`.
    fn m_stop(&mut self) {
        self.edo_motor = false;
        self.max_vel_clicks = 0;
        self.set_velocity();
    }

    /// `set_vel_giro_aux` / `set_vel_elev_aux`.
    fn set_vel_aux(&mut self, vel_clicks: i16) {
        self.max_vel_clicks = vel_clicks;
        self.set_velocity();
        self.turns_stop = 0;
        self.clicks_stop = 0;
        self.acelerando = false;
        self.frenando = false;
    }

    /// `set_params_giro` / `set_params_elev`.
    fn set_params(&mut self, p: u16) {
        self.turns_stop = p;
        self.clicks_stop = u32::from(p) * 1000;
        self.total_clicks = 0;
        self.g_clicks = 0;
        self.g_index = 0;
        self.clicks_break = self.clicks_stop / 2;
        self.timer_ac = self.k_ms_inc;
        self.acelerando = true;
        self.frenando = false;
    }

    /// `speed_control_giro` / `speed_control_elev`.
    fn speed_control(&mut self) {
        if !self.edo_motor {
            return;
        }
        let vel = i32::from(self.g_vel);
        self.total_clicks = self.total_clicks.wrapping_add(vel as u32);
        let error = self.k_pro * (i32::from(self.des_vel_clicks) - vel) / 100;
        self.bridge.pwm = limit_range(self.bridge.pwm, error);
    }

    /// `ac_control_giro` / `ac_control_elev`.
    fn ac_control(&mut self) {
        if self.turns_stop == 0 {
            return;
        }
        if self.timer_ac != 0 {
            self.timer_ac -= 1;
            return;
        }
        if self.acelerando {
            if i32::from(self.g_vel) + 3 >= i32::from(self.k_vel_end) {
                self.clicks_break = self.clicks_stop.wrapping_sub(self.total_clicks);
                self.acelerando = false;
            }
            if self.des_vel_clicks < self.k_vel_end {
                self.des_vel_clicks += 1;
            }
        }
        if self.frenando && self.des_vel_clicks > self.k_vel_ini {
            self.des_vel_clicks -= 1;
        }
        self.timer_ac = self.k_ms_inc;
    }

    /// The braking half of `check_stop_motor_giro` / `check_stop_motor_elev`.
    fn check_braking(&mut self) {
        if self.edo_motor && !self.frenando && self.total_clicks >= self.clicks_break {
            self.acelerando = false;
            self.frenando = true;
        }
    }

    /// `ISR_MGiroI` / `ISR_MElevI`: an index pulse. `strict` is the tilt's `>` instead of `>=`.
    fn index_pulse(&mut self, bypass: bool, strict: bool) {
        let clicks = i32::from(self.g_clicks).abs();
        let enough = if strict {
            clicks > OFFSET
        } else {
            clicks >= OFFSET
        };
        if bypass || enough {
            self.g_index = self.g_index.wrapping_add(1);
            self.abs = if self.dir {
                self.abs.wrapping_add(1)
            } else {
                self.abs.wrapping_sub(1)
            };
            if self.turns_stop != 0 && self.g_index >= self.turns_stop {
                self.m_stop();
                self.pos_control = true;
            }
            self.g_clicks = 0;
        }
    }
}

/// The state of the pan-tilt microcontroller.
#[derive(Clone, Debug)]
pub struct PanTiltFirmware {
    giro: Axis,
    elev: Axis,
    /// The limit switches as the inputs read them: pressed or not.
    tope_izq: bool,
    tope_der: bool,
    tope_inf: bool,
    g_offset_bypass: bool,
    g_timer: u16,
    edo_wait: u16,
    wait_for_motor_giro: bool,
    wait_for_motor_elev: bool,
    step: Step,
    param: [u16; MAX_PARAMS],
    tx: Vec<u8>,
}

impl PanTiltFirmware {
    /// The microcontroller after reset: `main` up to the greeting, and `init_control`. The
    /// switches are read as given.
    pub fn power_on(tope_izq: bool, tope_der: bool, tope_inf: bool) -> Self {
        let mut fw = PanTiltFirmware {
            giro: Axis::power_on(),
            elev: Axis::power_on(),
            tope_izq,
            tope_der,
            tope_inf,
            g_offset_bypass: false,
            g_timer: 0,
            edo_wait: 0,
            wait_for_motor_giro: false,
            wait_for_motor_elev: false,
            step: Step::GiroDerStart,
            param: [0; MAX_PARAMS],
            tx: Vec::new(),
        };
        fw.giro.set_velocity();
        fw.elev.set_velocity();
        fw.puts("Sistema ROCA-PANT-TILT v1.0\n");
        fw
    }

    // ------------------------------------------------------------------ interface to the twin

    /// The H-bridge inputs (pan, tilt).
    pub fn bridges(&self) -> (HBridge, HBridge) {
        (self.giro.bridge, self.elev.bridge)
    }

    /// Absolute positions (pan, tilt) as the firmware counts them.
    pub fn positions(&self) -> (i16, i16) {
        (self.giro.abs, self.elev.abs)
    }

    /// Whether each motor is on (pan, tilt).
    pub fn motors_on(&self) -> (bool, bool) {
        (self.giro.edo_motor, self.elev.edo_motor)
    }

    /// Whether the power-up homing has finished (`Listo` sent).
    pub fn homed(&self) -> bool {
        self.step == Step::Done
    }

    /// `ISR_RealTimeInt`: `g_timer`, and `get_vel` latching the pulse accumulators (pan,
    /// tilt), which saturate at 255.
    pub fn rti_interrupt(&mut self, pan_edges: u32, tilt_edges: u32) {
        if self.g_timer != 0 {
            self.g_timer -= 1;
        }
        self.giro.g_vel = pan_edges.min(255) as u8;
        self.elev.g_vel = tilt_edges.min(255) as u8;
    }

    /// `ISR_MGiroB` / `ISR_MElevB`: `n` rising edges of channel B, the axis turning up (pan
    /// left, tilt up) or down.
    pub fn channel_b(&mut self, tilt: bool, n: u32, up: bool) {
        let axis = if tilt { &mut self.elev } else { &mut self.giro };
        let step = if up { 2 } else { -2 };
        axis.g_clicks = axis.g_clicks.wrapping_add((step * n as i32) as i16);
    }

    /// `ISR_MGiroI` / `ISR_MElevI`: the index pulse of the pan or tilt motor.
    pub fn index_pulse(&mut self, tilt: bool) {
        if tilt {
            self.elev.index_pulse(self.g_offset_bypass, true);
        } else {
            self.giro.index_pulse(self.g_offset_bypass, false);
        }
    }

    /// The limit switches' levels; a switch being pressed fires its interrupt (pan switches).
    pub fn set_switches(&mut self, izq: bool, der: bool, inf: bool) {
        if der && !self.tope_der && !self.giro.dir {
            // ISR_MGiroTopeDer
            self.giro.m_stop();
        }
        if izq && !self.tope_izq && self.giro.dir {
            // ISR_MGiroTopeIzq
            self.giro.m_stop();
        }
        self.tope_izq = izq;
        self.tope_der = der;
        self.tope_inf = inf;
    }

    /// Decodes and executes one received command line.
    pub fn execute_line(&mut self, line: &[u8]) {
        let line = &line[..line.len().min(LINE_CAPACITY)];
        let (command, num_params) = super::decode_command(line, &mut self.param);
        self.do_command(command, num_params);
    }

    /// Takes the bytes written to the serial port since the last call.
    pub fn take_output(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.tx)
    }

    // ------------------------------------------------------------------ serial.c

    fn puts(&mut self, s: &str) {
        self.tx.extend_from_slice(s.as_bytes());
    }

    /// `ser0_putshort`: a signed decimal.
    fn putshort(&mut self, x: i16) {
        let mut s = String::new();
        let _ = write!(s, "{x}");
        self.puts(&s);
    }

    // ------------------------------------------------------------------ main.c

    /// `init_secuence(step)`: one pass of the power-up homing; true when the step is done.
    fn init_secuence(&mut self, s: Step) -> bool {
        use Step::*;
        match s {
            GiroDerStart => {
                if !self.tope_der {
                    self.giro.dir = false;
                    self.giro.set_vel_aux(-10);
                    self.puts("Girando a la derecha\n");
                }
                true
            }
            GiroDerEnd => {
                if self.tope_der {
                    self.puts("Se alcanzó el tope derecho\n");
                }
                self.tope_der
            }
            GiroIzqStart => {
                self.giro.dir = true;
                self.giro.set_vel_aux(2);
                self.puts("Girando a la izquierda\n");
                true
            }
            GiroIzqEnd => {
                if !self.tope_der {
                    self.giro.set_vel_aux(0);
                    self.puts("Se liberó el tope derecho\n");
                }
                !self.tope_der
            }
            Giro1IzqStart => {
                self.g_offset_bypass = true;
                self.giro.abs = -1;
                self.turn_left_aux(1);
                self.puts("Giro de 1 unidad\n");
                true
            }
            Giro1IzqEnd => {
                if !self.giro.edo_motor {
                    self.g_offset_bypass = false;
                    self.puts("Motor de giro apagado\n");
                }
                !self.giro.edo_motor
            }
            ElevAbajoStart => {
                if !self.tope_inf {
                    self.elev.dir = false;
                    self.elev.set_vel_aux(-10);
                    self.puts("Hacia abajo\n");
                }
                true
            }
            ElevAbajoEnd => {
                if self.tope_inf {
                    self.elev.set_vel_aux(0);
                    self.puts("Se alcanzó el tope inferior\n");
                }
                self.tope_inf
            }
            ElevArribaStart => {
                self.elev.dir = true;
                self.elev.set_vel_aux(2);
                self.puts("Hacia arriba\n");
                true
            }
            ElevArribaEnd => {
                if !self.tope_inf {
                    self.elev.set_vel_aux(0);
                    self.puts("Se liberó el tope inferior\n");
                }
                !self.tope_inf
            }
            Elev1ArribaStart => {
                self.g_offset_bypass = true;
                self.elev.abs = -1;
                self.go_up_aux(1);
                self.puts("Hacia arriba 1 unidad\n");
                true
            }
            Elev1ArribaEnd => {
                if !self.elev.edo_motor {
                    self.g_offset_bypass = false;
                    self.puts("Motor de inclinación apagado\n");
                }
                !self.elev.edo_motor
            }
            Ready => {
                self.puts("Listo\n");
                true
            }
            Done => false,
        }
    }

    // ------------------------------------------------------------------ control.c

    fn turn_left_aux(&mut self, p: u16) {
        if !self.tope_izq {
            self.giro.set_params(p);
            self.giro.dir = true;
            self.giro.max_vel_clicks = self.giro.k_vel_ini;
            self.giro.set_velocity();
        }
    }

    fn turn_right_aux(&mut self, p: u16) {
        if !self.tope_der {
            self.giro.set_params(p);
            self.giro.dir = false;
            self.giro.max_vel_clicks = self.giro.k_vel_ini.wrapping_neg();
            self.giro.set_velocity();
        }
    }

    fn go_up_aux(&mut self, p: u16) {
        self.elev.set_params(p);
        self.elev.max_vel_clicks = self.elev.k_vel_ini;
        self.elev.set_velocity();
        self.elev.dir = true;
    }

    fn go_down_aux(&mut self, p: u16) {
        if !self.tope_inf {
            self.elev.set_params(p);
            self.elev.max_vel_clicks = self.elev.k_vel_ini.wrapping_neg();
            self.elev.set_velocity();
            self.elev.dir = false;
        }
    }

    fn report_status(&mut self) {
        self.puts("l");
        let fields = [
            self.giro.abs,
            self.giro.g_clicks,
            self.elev.abs,
            self.elev.g_clicks,
            i16::from(self.tope_izq),
            i16::from(self.tope_der),
            i16::from(self.tope_inf),
            i16::from(self.giro.edo_motor),
            i16::from(self.elev.edo_motor),
        ];
        for (i, f) in fields.iter().enumerate() {
            if i > 0 {
                self.puts(" ");
            }
            self.putshort(*f);
        }
        self.puts("\n");
    }

    fn check_stop_motor_elev(&mut self) {
        if self.elev.max_vel_clicks < 0 && self.tope_inf {
            self.elev.m_stop();
        }
        self.elev.check_braking();
    }

    fn do_abs_giro(&mut self, num_params: i32) {
        self.puts("g\n");
        if num_params > 0 {
            let target = self.param[0].min(MAX_ABS_GIRO);
            let dif = (target as i16).wrapping_sub(self.giro.abs);
            if dif > 0 {
                self.turn_left_aux(dif as u16);
            } else if dif < 0 {
                self.turn_right_aux(dif.wrapping_neg() as u16);
            }
        }
    }

    fn do_abs_elev(&mut self, num_params: i32) {
        self.puts("e\n");
        if num_params > 0 {
            let target = self.param[0].min(MAX_ABS_ELEV);
            let dif = (target as i16).wrapping_sub(self.elev.abs);
            if dif > 0 {
                self.go_up_aux(dif as u16);
            } else if dif < 0 {
                self.go_down_aux(dif.wrapping_neg() as u16);
            }
        }
    }

    fn set_ac(&mut self, tilt: bool) {
        self.puts(if tilt { "K\n" } else { "k\n" });
        let axis = if tilt { &mut self.elev } else { &mut self.giro };
        axis.k_vel_ini = self.param[0] as i16;
        axis.k_vel_end = self.param[1] as i16;
        axis.k_ms_inc = self.param[2] as i16;
    }

    // ------------------------------------------------------------------ command.c

    fn wait(&mut self, num_params: i32) {
        self.g_timer = self.param[0];
        if num_params == 3 {
            self.wait_for_motor_giro = self.param[1] != 0;
            self.wait_for_motor_elev = self.param[2] != 0;
        } else {
            self.wait_for_motor_giro = false;
            self.wait_for_motor_elev = false;
        }
        self.edo_wait = 1;
    }

    fn check_end_wait(&mut self) {
        if self.edo_wait != 0 {
            self.edo_wait = 0;
            if self.wait_for_motor_giro && self.giro.edo_motor {
                self.edo_wait = 1;
            }
            if self.wait_for_motor_elev && self.elev.edo_motor {
                self.edo_wait = 1;
            }
            // As written in the firmware, `!(Fg && !Fe) || edo_wait`: only "wait for the pan
            // alone" can end early.
            #[allow(clippy::nonminimal_bool)]
            let keep_waiting =
                !(self.wait_for_motor_giro && !self.wait_for_motor_elev) || self.edo_wait != 0;
            if keep_waiting {
                self.edo_wait = self.g_timer;
            }
            if self.edo_wait == 0 {
                self.puts("w\n");
            }
        }
    }

    fn query(&mut self) {
        // `ce[]` is never written: 251 zeros.
        for _ in 0..251 {
            self.puts("0 ");
        }
        self.puts("\n");
    }

    fn check_end_commands(&mut self) {
        self.check_end_wait();
        self.giro.check_braking();
        self.check_stop_motor_elev();
    }

    fn do_command(&mut self, command: u8, num_params: i32) {
        match command {
            b'w' => self.wait(num_params),
            b'q' => self.query(),
            b'k' => self.set_ac(false),
            b'K' => self.set_ac(true),
            b'g' => self.do_abs_giro(num_params),
            b'e' => self.do_abs_elev(num_params),
            b'l' => self.report_status(),
            b'*' => self.puts("*\n"),
            _ => {}
        }
        self.check_end_commands();
    }
}

impl MainLoop for PanTiltFirmware {
    fn execute_line(&mut self, line: &[u8]) {
        PanTiltFirmware::execute_line(self, line);
    }

    /// `check_rtf`, `check_end_commands` and a step of `init_secuence`, as `main` loops.
    fn after_interrupt(&mut self) {
        self.giro.speed_control();
        self.elev.speed_control();
        self.giro.ac_control();
        self.elev.ac_control();
        self.check_end_commands();
        if self.step < Step::Done && self.init_secuence(self.step) {
            self.step = self.step.next();
        }
    }

    fn take_output(&mut self) -> Vec<u8> {
        PanTiltFirmware::take_output(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reply(fw: &mut PanTiltFirmware, line: &str) -> String {
        fw.execute_line(line.as_bytes());
        String::from_utf8(fw.take_output()).unwrap()
    }

    fn homed() -> PanTiltFirmware {
        let mut fw = PanTiltFirmware::power_on(false, false, false);
        fw.step = Step::Done;
        fw.take_output();
        fw
    }

    #[test]
    fn greets_and_answers_its_commands() {
        let mut fw = PanTiltFirmware::power_on(false, false, false);
        assert_eq!(fw.take_output(), b"Sistema ROCA-PANT-TILT v1.0\n");
        assert_eq!(reply(&mut fw, "*\n"), "*\n");
        assert_eq!(reply(&mut fw, "k3 50 30\n"), "k\n");
        assert_eq!(reply(&mut fw, "K3 50 30\n"), "K\n");
        assert_eq!(reply(&mut fw, "p\n"), "", "the firmware has no `p`");
        assert_eq!(reply(&mut fw, "l\n"), "l0 0 0 0 0 0 0 0 0\n");
        assert!(reply(&mut fw, "q\n").starts_with("0 0 0"));
    }

    #[test]
    fn a_move_counts_index_pulses_and_stops_at_the_last() {
        let mut fw = homed();
        assert_eq!(reply(&mut fw, "g3\n"), "g\n");
        assert_eq!(fw.motors_on(), (true, false));
        for _ in 0..3 {
            fw.channel_b(false, 500, true);
            fw.index_pulse(false);
        }
        assert_eq!(fw.positions().0, 3);
        assert_eq!(fw.motors_on(), (false, false));
        // Back to 1: two pulses turning right.
        reply(&mut fw, "g1\n");
        for _ in 0..2 {
            fw.channel_b(false, 500, false);
            fw.index_pulse(false);
        }
        assert_eq!(fw.positions().0, 1);
    }

    #[test]
    fn an_index_pulse_without_enough_clicks_is_not_counted() {
        let mut fw = homed();
        reply(&mut fw, "e5\n");
        fw.channel_b(true, 500, true);
        fw.index_pulse(true);
        fw.channel_b(true, 100, false); // hovering back across the index
        fw.index_pulse(true);
        assert_eq!(fw.positions().1, 1);
    }

    #[test]
    fn targets_are_clamped_to_the_firmware_limits() {
        let mut fw = homed();
        reply(&mut fw, "g254\n");
        assert_eq!(fw.giro.turns_stop, MAX_ABS_GIRO);
        reply(&mut fw, "e200\n");
        assert_eq!(fw.elev.turns_stop, MAX_ABS_ELEV);
    }

    #[test]
    fn waiting_for_both_motors_waits_the_full_time() {
        let mut fw = homed();
        assert_eq!(reply(&mut fw, "w3 1 1\n"), "", "idle motors, yet it waits");
        for _ in 0..2 {
            fw.rti_interrupt(0, 0);
            fw.after_interrupt();
        }
        assert_eq!(fw.take_output(), b"");
        fw.rti_interrupt(0, 0);
        fw.after_interrupt();
        assert_eq!(fw.take_output(), b"w\n");
        // Waiting for the pan alone ends as soon as the pan is idle.
        assert_eq!(reply(&mut fw, "w1000 1 0\n"), "w\n");
    }

    #[test]
    fn the_pan_stops_on_the_switch_it_runs_into() {
        let mut fw = homed();
        reply(&mut fw, "g100\n");
        fw.set_switches(true, false, false);
        assert!(!fw.motors_on().0);
        assert_eq!(reply(&mut fw, "g200\n"), "g\n");
        assert!(!fw.motors_on().0, "no move towards a pressed switch");
    }
}
