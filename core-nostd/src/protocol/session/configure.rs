//! The configuration requests: `CFG`, `DRIVE`, `LIMITS`.

use super::*;

impl Session {
    #[inline(never)]
    pub(super) fn cfg_command<'a, I: Io>(&mut self, args: &Args<'a>, io: &mut I) -> Outcome<'a> {
        let [hx, hz, diam, rn, tip, tol, pass] = args.values();
        let mut cfg = self.cfg;
        if let Some(v) = hx {
            cfg.hx = parse_price("HX", v)?;
        }
        if let Some(v) = hz {
            cfg.hz = parse_price("HZ", v)?;
        }
        if let Some(v) = diam {
            cfg.diam = parse_flag("DIAM", v)?;
        }
        if rn.is_some() || tip.is_some() {
            self.not_compensating("CFG RN or TIP")?;
        }
        if let Some(v) = rn {
            cfg.rn = parse_bounded("RN", v, 0, MAX_NOSE_RADIUS_UM, "must be 0 to 25 mm")?;
        }
        if let Some(v) = tip {
            cfg.tip = match v.as_bytes() {
                [d @ b'0'..=b'9'] => TipCode::new(d - b'0'),
                _ => None,
            }
            .ok_or(Refusal::Value("TIP", "must be a digit 0 to 9"))?;
        }
        if let Some(v) = tol {
            cfg.tol = parse_tol(v)?;
        }
        if let Some(v) = pass {
            cfg.pass = parse_pass(v)?;
        }
        // A new price re-expresses the registers at the same commanded point.
        let pos = ImpulsePoint {
            x: quantize(self.cmd[0], cfg.hx).map_err(|_| Refusal::Range(RANGE_POS_X))?,
            z: quantize(self.cmd[1], cfg.hz).map_err(|_| Refusal::Range(RANGE_POS_Z))?,
        };
        if let Some(axis) = self
            .machine
            .limits()
            .too_fast([cfg.hx, cfg.hz], self.drive.rate_hz())
        {
            let key = ["HX", "HZ"][axis & 1];
            return Err(Refusal::Value(
                key,
                "needs more step events than DRIVE RATE at the rapid rate",
            ));
        }
        if (cfg.hx, cfg.hz) != (self.cfg.hx, self.cfg.hz) {
            // New prices re-express the registers: at rest.
            self.machine.flush(&mut Sink::new(io, self.drive));
            self.machine
                .set_position(point_q32(self.cmd), pos, &mut Sink::new(io, self.drive));
        }
        self.cfg = cfg;
        self.pos = pos;
        self.apply_backlash();
        let c = &self.cfg;
        send_ok(
            io,
            Some(format_args!(
                "HX={} HZ={} DIAM={} RN={} TIP={} TOL={} PASS={}",
                c.hx.as_length(),
                c.hz.as_length(),
                u8::from(c.diam),
                c.rn,
                c.tip.get(),
                c.tol,
                c.pass.as_str()
            )),
        );
        Ok(())
    }

    #[inline(never)]
    pub(super) fn drive_command<'a, I: Io>(&mut self, args: &Args<'a>, io: &mut I) -> Outcome<'a> {
        let [rate, pulse, setup] = args.values();
        let d = self.drive;
        let rate = parse_count("RATE", rate, d.rate_hz())?;
        let pulse = parse_count("PULSE", pulse, d.pulse_us())?;
        let setup = parse_count("SETUP", setup, d.setup_us())?;
        let drive = DriveTiming::new(rate, pulse, setup).map_err(|e| match e {
            TimingError::Rate => Refusal::Value("RATE", "must be 1 to 200000 steps/s"),
            TimingError::Pulse => Refusal::Value("PULSE", "must be 1 to 1000 us"),
            TimingError::Setup => Refusal::Value("SETUP", "must be 0 to 1000 us"),
            TimingError::PulseTooLong => Refusal::Value("PULSE", "longer than a step period"),
        })?;
        if self
            .machine
            .limits()
            .too_fast([self.cfg.hx, self.cfg.hz], drive.rate_hz())
            .is_some()
        {
            return Err(Refusal::Value(
                "RATE",
                "below what the rapid rates need (VX/HX, VZ/HZ)",
            ));
        }
        if drive != self.drive {
            self.machine.flush(&mut Sink::new(io, self.drive));
            self.drive = drive;
        }
        send_ok(
            io,
            Some(format_args!(
                "RATE={} PULSE={} SETUP={}",
                self.drive.rate_hz(),
                self.drive.pulse_us(),
                self.drive.setup_us()
            )),
        );
        Ok(())
    }

    /// `LIMITS [VX=] [VZ=] [AX=] [AZ=] [JD=]`: the motion limits, applied
    /// whole at rest, or reported.
    #[inline(never)]
    pub(super) fn limits_command<'a, I: Io>(&mut self, args: &Args<'a>, io: &mut I) -> Outcome<'a> {
        let keys = ["VX", "VZ", "AX", "AZ", "JD"];
        let values: [_; 5] = args.values();
        let now = *self.machine.limits();
        let old = [
            now.rate(0),
            now.rate(1),
            now.accel(0),
            now.accel(1),
            now.junction(),
        ];
        let mut v = old;
        for ((slot, value), key) in v.iter_mut().zip(values).zip(keys) {
            if let Some(text) = value {
                *slot = parse_rate(key, text, Refusal::Value(key, "too large"))?;
            }
        }
        let limits = Limits::new([v[0], v[1]], [v[2], v[3]], v[4]).map_err(|e| match e {
            LimitsError::Rate(0) => {
                Refusal::Value("VX", "must be over 0, at most 99999.999999 mm/min")
            }
            LimitsError::Rate(_) => {
                Refusal::Value("VZ", "must be over 0, at most 99999.999999 mm/min")
            }
            LimitsError::Accel(0) => Refusal::Value("AX", "must be 10 to 99999.999999 mm/s2"),
            LimitsError::Accel(_) => Refusal::Value("AZ", "must be 10 to 99999.999999 mm/s2"),
            LimitsError::Junction => Refusal::Value("JD", "must be 0 to 10 mm"),
        })?;
        if let Some(axis) = limits.too_fast([self.cfg.hx, self.cfg.hz], self.drive.rate_hz()) {
            let key = ["VX", "VZ"][axis & 1];
            return Err(Refusal::Value(
                key,
                "needs more step events than DRIVE RATE",
            ));
        }
        if limits != now {
            self.machine.flush(&mut Sink::new(io, self.drive));
            self.machine.set_limits(limits);
        }
        let l = self.machine.limits();
        send_ok(
            io,
            Some(format_args!(
                "VX={} VZ={} AX={} AZ={} JD={} TICK={} LOOKAHEAD={}",
                l.rate(0),
                l.rate(1),
                l.accel(0),
                l.accel(1),
                l.junction(),
                self.machine.tick().hz(),
                WINDOW
            )),
        );
        Ok(())
    }
}
