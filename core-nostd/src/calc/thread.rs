//! The highest spindle speed a thread can be cut at (the ЭМ-907 rule, and
//! this controller's axis limits).
//!
//! Threading couples the spindle to an axis: one revolution moves the axis
//! by the pitch `t`, so the axis feed is `n·t` mm/min at `n` rpm and must
//! not exceed what the axis can do, `n ≤ v_max / t` ([`max_speed_rpm`]).
//!
//! The ЭМ-907 (Kosenko 1977, ch. VI) writes that rule for the 16Б16Ф3's
//! working feeds, 1200 mm/min on the carriage (0.01 mm impulses) and
//! 600 mm/min on the cross slide (0.005 mm impulses), and adds a speed cap
//! per threading mode ([`em907_max_speed_rpm`]):
//!
//! | mode | pitch word | largest pitch along / across | cap | cap reached up to |
//! |---|---|---|---|---|
//! | G06 | pitch ×1 | 10 mm / 5 mm | 240 rpm | 5 mm / 2.5 mm |
//! | G07 | pitch ×2 | 5 mm / 2.5 mm | 480 rpm | 2.5 mm / 1.25 mm |
//! | G08 | pitch ×4 | 2.5 mm / 1.25 mm | 960 rpm | 1.25 mm / 0.625 mm |
//! | G09 | pitch ×8 | 1.25 mm / 0.625 mm | 1920 rpm | 0.625 mm / 0.3125 mm |
//!
//! `n_max = min(cap, 1200/t)` along, `min(cap, 600/t)` across. The pitch
//! word (address K along, J across) is the pitch times the mode's factor
//! in impulses of that axis, at most 1000. The seed prints the G09 cap as
//! 19200 rpm; it is 1920 (= 1200/0.625, the pattern of the other three
//! modes; `docs/errata.md` §2.7).

use core::fmt;

/// Why a threading speed cannot be given.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ThreadError {
    /// The pitch is zero, negative or not a number.
    PitchNotPositive,
    /// The pitch is coarser than the mode cuts on that axis (its pitch word
    /// would exceed 1000 impulses).
    PitchTooCoarse,
    /// The pitch is finer than one unit of the mode's pitch word.
    PitchTooFine,
    /// The pitch is not a whole number of the mode's pitch-word units.
    PitchOffGrid,
    /// A G code that is not one of the threading modes G06–G09.
    UnknownMode,
    /// The axis feed limit is zero, negative or not a number.
    FeedLimitNotPositive,
}

impl ThreadError {
    /// A short, fixed description naming the input and why it is refused.
    ///
    /// ```
    /// use core_nostd::calc::thread::ThreadError;
    /// assert_eq!(ThreadError::PitchNotPositive.as_str(), "pitch: not a positive number of mm");
    /// ```
    pub const fn as_str(self) -> &'static str {
        match self {
            ThreadError::PitchNotPositive => "pitch: not a positive number of mm",
            ThreadError::PitchTooCoarse => "pitch: coarser than the mode cuts on this axis",
            ThreadError::PitchTooFine => "pitch: finer than one unit of the mode's pitch word",
            ThreadError::PitchOffGrid => "pitch: not a whole number of the mode's pitch-word units",
            ThreadError::UnknownMode => "mode: not a threading mode G06-G09",
            ThreadError::FeedLimitNotPositive => "feed limit: not a positive number of mm/min",
        }
    }
}

impl fmt::Display for ThreadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// The axis a thread's pitch runs along, with the ЭМ-907's impulse price
/// and working feed limit on it (16Б16Ф3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ThreadAxis {
    /// Along the spindle (Z, the carriage; a cylindrical thread): 0.01 mm
    /// impulses, 1200 mm/min.
    Longitudinal,
    /// Across the spindle (X, the cross slide; a face thread, an
    /// Archimedean spiral): 0.005 mm impulses, 600 mm/min.
    Across,
}

impl ThreadAxis {
    /// The ЭМ-907 impulse price on this axis, mm.
    ///
    /// ```
    /// use core_nostd::calc::thread::ThreadAxis;
    /// assert_eq!(ThreadAxis::Longitudinal.impulse_mm(), 0.01);
    /// assert_eq!(ThreadAxis::Across.impulse_mm(), 0.005);
    /// ```
    pub const fn impulse_mm(self) -> f64 {
        match self {
            ThreadAxis::Longitudinal => 0.01,
            ThreadAxis::Across => 0.005,
        }
    }

    /// The 16Б16Ф3's highest working feed on this axis, mm/min: the
    /// numerator of the ЭМ-907's `n_max = 1200/t` (`600/t` across).
    ///
    /// ```
    /// use core_nostd::calc::thread::ThreadAxis;
    /// assert_eq!(ThreadAxis::Longitudinal.feed_limit_mm_min(), 1200.0);
    /// assert_eq!(ThreadAxis::Across.feed_limit_mm_min(), 600.0);
    /// ```
    pub const fn feed_limit_mm_min(self) -> f64 {
        match self {
            ThreadAxis::Longitudinal => 1200.0,
            ThreadAxis::Across => 600.0,
        }
    }
}

/// The largest pitch word, impulses (addresses J and K).
const PITCH_WORD_MAX: f64 = 1000.0;

/// One of the ЭМ-907's threading modes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ThreadMode {
    /// G06: the pitch programmed as it is, up to 240 rpm.
    G06,
    /// G07: twice the pitch programmed, up to 480 rpm.
    G07,
    /// G08: four times the pitch programmed, up to 960 rpm.
    G08,
    /// G09: eight times the pitch programmed, up to 1920 rpm.
    G09,
}

impl ThreadMode {
    /// The mode of a G code number (6 to 9).
    ///
    /// ```
    /// use core_nostd::calc::thread::{ThreadError, ThreadMode};
    /// assert_eq!(ThreadMode::from_g_code(8), Ok(ThreadMode::G08));
    /// assert_eq!(ThreadMode::from_g_code(5), Err(ThreadError::UnknownMode));
    /// assert_eq!(ThreadMode::from_g_code(10), Err(ThreadError::UnknownMode));
    /// ```
    pub const fn from_g_code(code: u16) -> Result<Self, ThreadError> {
        match code {
            6 => Ok(ThreadMode::G06),
            7 => Ok(ThreadMode::G07),
            8 => Ok(ThreadMode::G08),
            9 => Ok(ThreadMode::G09),
            _ => Err(ThreadError::UnknownMode),
        }
    }

    /// The G code number of the mode.
    ///
    /// ```
    /// use core_nostd::calc::thread::ThreadMode;
    /// assert_eq!(ThreadMode::G06.g_code(), 6);
    /// ```
    pub const fn g_code(self) -> u16 {
        match self {
            ThreadMode::G06 => 6,
            ThreadMode::G07 => 7,
            ThreadMode::G08 => 8,
            ThreadMode::G09 => 9,
        }
    }

    /// How many times the pitch the pitch word holds: 1, 2, 4, 8.
    ///
    /// ```
    /// use core_nostd::calc::thread::ThreadMode;
    /// assert_eq!(ThreadMode::G09.pitch_factor(), 8);
    /// ```
    pub const fn pitch_factor(self) -> u16 {
        match self {
            ThreadMode::G06 => 1,
            ThreadMode::G07 => 2,
            ThreadMode::G08 => 4,
            ThreadMode::G09 => 8,
        }
    }

    /// The mode's spindle speed cap, rpm: 240, 480, 960, 1920 (the seed's
    /// "19200" for G09 is a misprint).
    ///
    /// ```
    /// use core_nostd::calc::thread::ThreadMode;
    /// assert_eq!(ThreadMode::G09.speed_cap_rpm(), 1920.0);
    /// ```
    pub const fn speed_cap_rpm(self) -> f64 {
        match self {
            ThreadMode::G06 => 240.0,
            ThreadMode::G07 => 480.0,
            ThreadMode::G08 => 960.0,
            ThreadMode::G09 => 1920.0,
        }
    }

    /// The coarsest pitch the mode cuts on an axis, mm: a full pitch word
    /// (1000 impulses) over the mode's factor. Along: 10, 5, 2.5, 1.25 mm;
    /// across half of that.
    ///
    /// ```
    /// use core_nostd::calc::thread::{ThreadAxis, ThreadMode};
    /// assert_eq!(ThreadMode::G07.max_pitch_mm(ThreadAxis::Longitudinal), 5.0);
    /// assert_eq!(ThreadMode::G07.max_pitch_mm(ThreadAxis::Across), 2.5);
    /// ```
    pub fn max_pitch_mm(self, axis: ThreadAxis) -> f64 {
        PITCH_WORD_MAX * axis.impulse_mm() / f64::from(self.pitch_factor())
    }

    /// The pitch word of the mode, its unit: the axis' impulse over the
    /// factor, mm (G06 along 0.01 mm, G09 along 0.00125 mm).
    fn word_unit_mm(self, axis: ThreadAxis) -> f64 {
        axis.impulse_mm() / f64::from(self.pitch_factor())
    }
}

/// Checks that a pitch is a positive, finite number of mm.
fn positive(pitch_mm: f64) -> Result<f64, ThreadError> {
    // `!(x > 0)` also refuses NaN; the upper bound refuses +∞.
    if !(pitch_mm > 0.0 && pitch_mm < f64::MAX) {
        return Err(ThreadError::PitchNotPositive);
    }
    Ok(pitch_mm)
}

/// The ЭМ-907's highest spindle speed, rpm, for a thread of pitch
/// `pitch_mm` cut in `mode` along `axis`: `min(cap, 1200/t)` along,
/// `min(cap, 600/t)` across. A pitch coarser than the mode cuts there
/// ([`ThreadMode::max_pitch_mm`]) is refused.
///
/// ```
/// use core_nostd::calc::thread::{em907_max_speed_rpm, ThreadAxis, ThreadError, ThreadMode};
/// let along = ThreadAxis::Longitudinal;
/// // G06: the cap up to a 5 mm pitch, then 1200/t.
/// assert_eq!(em907_max_speed_rpm(ThreadMode::G06, along, 3.0), Ok(240.0));
/// assert_eq!(em907_max_speed_rpm(ThreadMode::G06, along, 8.0), Ok(150.0));
/// // G09 reaches 1920 rpm up to 0.625 mm.
/// assert_eq!(em907_max_speed_rpm(ThreadMode::G09, along, 0.5), Ok(1920.0));
/// assert_eq!(em907_max_speed_rpm(ThreadMode::G09, along, 1.0), Ok(1200.0));
/// // Across (face threads): 600/t, pitches halved.
/// assert_eq!(em907_max_speed_rpm(ThreadMode::G06, ThreadAxis::Across, 4.0), Ok(150.0));
/// assert_eq!(
///     em907_max_speed_rpm(ThreadMode::G08, along, 3.0),
///     Err(ThreadError::PitchTooCoarse)
/// );
/// assert_eq!(
///     em907_max_speed_rpm(ThreadMode::G06, along, 0.0),
///     Err(ThreadError::PitchNotPositive)
/// );
/// ```
pub fn em907_max_speed_rpm(
    mode: ThreadMode,
    axis: ThreadAxis,
    pitch_mm: f64,
) -> Result<f64, ThreadError> {
    let t = positive(pitch_mm)?;
    if t > mode.max_pitch_mm(axis) {
        return Err(ThreadError::PitchTooCoarse);
    }
    Ok(mode.speed_cap_rpm().min(axis.feed_limit_mm_min() / t))
}

/// The ЭМ-907 pitch word (K along, J across) for a pitch: the pitch times
/// the mode's factor, in impulses of the axis, 1 to 1000. The pitch must be
/// a whole number of the word's units (G06 along: 0.01 mm; G09 along:
/// 0.00125 mm), within 10⁻⁶ of a unit.
///
/// ```
/// use core_nostd::calc::thread::{em907_pitch_word, ThreadAxis, ThreadError, ThreadMode};
/// let along = ThreadAxis::Longitudinal;
/// assert_eq!(em907_pitch_word(ThreadMode::G06, along, 10.0), Ok(1000));
/// assert_eq!(em907_pitch_word(ThreadMode::G07, along, 2.5), Ok(500));
/// assert_eq!(em907_pitch_word(ThreadMode::G09, along, 1.25), Ok(1000));
/// assert_eq!(em907_pitch_word(ThreadMode::G06, ThreadAxis::Across, 5.0), Ok(1000));
/// assert_eq!(em907_pitch_word(ThreadMode::G06, along, 1.005), Err(ThreadError::PitchOffGrid));
/// assert_eq!(em907_pitch_word(ThreadMode::G09, along, 1.5), Err(ThreadError::PitchTooCoarse));
/// assert_eq!(em907_pitch_word(ThreadMode::G06, along, 0.004), Err(ThreadError::PitchTooFine));
/// ```
pub fn em907_pitch_word(
    mode: ThreadMode,
    axis: ThreadAxis,
    pitch_mm: f64,
) -> Result<u16, ThreadError> {
    let t = positive(pitch_mm)?;
    if t > mode.max_pitch_mm(axis) * (1.0 + 1e-9) {
        return Err(ThreadError::PitchTooCoarse);
    }
    let units = t / mode.word_unit_mm(axis);
    let word = libm::round(units);
    if word < 1.0 {
        return Err(ThreadError::PitchTooFine);
    }
    if libm::fabs(units - word) > 1e-6 {
        return Err(ThreadError::PitchOffGrid);
    }
    // 1 ≤ word ≤ 1000 here (the pitch is at most a full word), so the
    // conversion is exact; the clamp only spells that out.
    Ok(word.min(PITCH_WORD_MAX) as u16)
}

/// The ЭМ-907 mode that cuts a pitch fastest: the finest mode whose largest
/// pitch holds it (a finer mode has the higher cap, and where `1200/t`
/// limits, every mode that holds the pitch gives the same speed).
///
/// ```
/// use core_nostd::calc::thread::{fastest_em907_mode, ThreadAxis, ThreadError, ThreadMode};
/// let along = ThreadAxis::Longitudinal;
/// assert_eq!(fastest_em907_mode(along, 1.0), Ok(ThreadMode::G09));
/// assert_eq!(fastest_em907_mode(along, 2.0), Ok(ThreadMode::G08));
/// assert_eq!(fastest_em907_mode(along, 6.0), Ok(ThreadMode::G06));
/// assert_eq!(fastest_em907_mode(along, 12.0), Err(ThreadError::PitchTooCoarse));
/// ```
pub fn fastest_em907_mode(axis: ThreadAxis, pitch_mm: f64) -> Result<ThreadMode, ThreadError> {
    let t = positive(pitch_mm)?;
    [
        ThreadMode::G09,
        ThreadMode::G08,
        ThreadMode::G07,
        ThreadMode::G06,
    ]
    .into_iter()
    .find(|mode| t <= mode.max_pitch_mm(axis))
    .ok_or(ThreadError::PitchTooCoarse)
}

/// This controller's rule: the highest spindle speed, rpm, at which the
/// axis the pitch runs along keeps within its feed limit,
/// `n_max = v_max / t` (`v_max` mm/min, `t` mm). The spindle's own top
/// speed is a separate limit for the caller to apply.
///
/// ```
/// use core_nostd::calc::thread::{max_speed_rpm, ThreadError};
/// // A 1.5 mm pitch on an axis limited to 3000 mm/min.
/// assert_eq!(max_speed_rpm(3000.0, 1.5), Ok(2000.0));
/// // The ЭМ-907's carriage, 1200 mm/min, at a 5 mm pitch.
/// assert_eq!(max_speed_rpm(1200.0, 5.0), Ok(240.0));
/// assert_eq!(max_speed_rpm(3000.0, -1.0), Err(ThreadError::PitchNotPositive));
/// assert_eq!(max_speed_rpm(0.0, 1.0), Err(ThreadError::FeedLimitNotPositive));
/// ```
pub fn max_speed_rpm(feed_limit_mm_min: f64, pitch_mm: f64) -> Result<f64, ThreadError> {
    if !(feed_limit_mm_min > 0.0 && feed_limit_mm_min < f64::MAX) {
        return Err(ThreadError::FeedLimitNotPositive);
    }
    let t = positive(pitch_mm)?;
    Ok(feed_limit_mm_min / t)
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALONG: ThreadAxis = ThreadAxis::Longitudinal;
    const ACROSS: ThreadAxis = ThreadAxis::Across;
    const MODES: [ThreadMode; 4] = [
        ThreadMode::G06,
        ThreadMode::G07,
        ThreadMode::G08,
        ThreadMode::G09,
    ];

    fn close(a: f64, b: f64) -> bool {
        libm::fabs(a - b) <= 1e-9 * libm::fabs(b).max(1.0)
    }

    /// The seed's numbers: each mode's largest pitch, its cap, and the pitch
    /// above which `1200/t` lowers the speed ("свыше 5 мм", 2.5, 1.25,
    /// 0.625 mm).
    #[test]
    fn seed_modes() {
        let table = [
            (ThreadMode::G06, 10.0, 240.0, 5.0),
            (ThreadMode::G07, 5.0, 480.0, 2.5),
            (ThreadMode::G08, 2.5, 960.0, 1.25),
            (ThreadMode::G09, 1.25, 1920.0, 0.625),
        ];
        for (mode, t_max, cap, knee) in table {
            assert_eq!(mode.max_pitch_mm(ALONG), t_max);
            assert_eq!(mode.speed_cap_rpm(), cap);
            // The cap is exactly 1200/t at the knee: the seed's 19200 for G09
            // would put the knee at 0.0625 mm, against its own 0.625.
            assert!(close(1200.0 / knee, cap));
            assert_eq!(em907_max_speed_rpm(mode, ALONG, knee), Ok(cap));
            assert_eq!(em907_max_speed_rpm(mode, ALONG, knee / 2.0), Ok(cap));
            assert_eq!(em907_max_speed_rpm(mode, ALONG, t_max), Ok(1200.0 / t_max));
            assert_eq!(em907_pitch_word(mode, ALONG, t_max), Ok(1000));
            assert_eq!(
                em907_max_speed_rpm(mode, ALONG, t_max * 1.001),
                Err(ThreadError::PitchTooCoarse)
            );
        }
        assert_eq!(em907_max_speed_rpm(ThreadMode::G06, ALONG, 10.0), Ok(120.0));
    }

    /// Face threads: the impulse halves (0.005 mm), so do the pitches and
    /// the feed (600 mm/min); the caps stay.
    #[test]
    fn across_halves_the_pitches() {
        for mode in MODES {
            let t_max = mode.max_pitch_mm(ACROSS);
            assert_eq!(t_max, mode.max_pitch_mm(ALONG) / 2.0);
            assert!(close(600.0 / (t_max / 2.0), mode.speed_cap_rpm()));
            assert_eq!(em907_max_speed_rpm(mode, ACROSS, t_max), Ok(600.0 / t_max));
            assert_eq!(em907_pitch_word(mode, ACROSS, t_max), Ok(1000));
        }
        assert_eq!(em907_max_speed_rpm(ThreadMode::G06, ACROSS, 5.0), Ok(120.0));
        assert_eq!(
            em907_max_speed_rpm(ThreadMode::G06, ACROSS, 6.0),
            Err(ThreadError::PitchTooCoarse)
        );
    }

    #[test]
    fn pitch_words() {
        assert_eq!(em907_pitch_word(ThreadMode::G06, ALONG, 0.01), Ok(1));
        assert_eq!(em907_pitch_word(ThreadMode::G06, ALONG, 1.5), Ok(150));
        assert_eq!(em907_pitch_word(ThreadMode::G07, ALONG, 1.5), Ok(300));
        assert_eq!(em907_pitch_word(ThreadMode::G08, ALONG, 1.75), Ok(700));
        assert_eq!(em907_pitch_word(ThreadMode::G09, ALONG, 0.75), Ok(600));
        assert_eq!(em907_pitch_word(ThreadMode::G09, ALONG, 0.00125), Ok(1));
        assert_eq!(em907_pitch_word(ThreadMode::G06, ACROSS, 1.005), Ok(201));
        assert_eq!(
            em907_pitch_word(ThreadMode::G06, ALONG, 1.005),
            Err(ThreadError::PitchOffGrid)
        );
        assert_eq!(
            em907_pitch_word(ThreadMode::G08, ALONG, 0.001),
            Err(ThreadError::PitchTooFine)
        );
    }

    #[test]
    fn fastest_mode_is_never_slower() {
        for k in 1..=1000 {
            let t = f64::from(k) * 0.01;
            let best = fastest_em907_mode(ALONG, t).map(|m| em907_max_speed_rpm(m, ALONG, t));
            for mode in MODES {
                if let Ok(n) = em907_max_speed_rpm(mode, ALONG, t) {
                    assert!(matches!(best, Ok(Ok(b)) if b >= n));
                }
            }
        }
    }

    #[test]
    fn controller_rule() {
        assert_eq!(max_speed_rpm(1200.0, 2.0), Ok(600.0));
        assert_eq!(max_speed_rpm(600.0, 2.0), Ok(300.0));
        assert_eq!(max_speed_rpm(5000.0, 0.5), Ok(10000.0));
        // The ЭМ-907 rule is the same one below its cap.
        for t in [5.5, 7.0, 10.0] {
            assert_eq!(
                max_speed_rpm(ALONG.feed_limit_mm_min(), t),
                em907_max_speed_rpm(ThreadMode::G06, ALONG, t)
            );
        }
    }

    #[test]
    fn domain_errors() {
        for t in [0.0, -0.0, -1.5, f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert_eq!(
                em907_max_speed_rpm(ThreadMode::G06, ALONG, t),
                Err(ThreadError::PitchNotPositive)
            );
            assert_eq!(
                em907_pitch_word(ThreadMode::G06, ALONG, t),
                Err(ThreadError::PitchNotPositive)
            );
            assert_eq!(
                fastest_em907_mode(ALONG, t),
                Err(ThreadError::PitchNotPositive)
            );
            assert_eq!(max_speed_rpm(1200.0, t), Err(ThreadError::PitchNotPositive));
        }
        for v in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(
                max_speed_rpm(v, 1.0),
                Err(ThreadError::FeedLimitNotPositive)
            );
        }
        for code in [0, 1, 5, 10, 90, u16::MAX] {
            assert_eq!(ThreadMode::from_g_code(code), Err(ThreadError::UnknownMode));
        }
        for mode in MODES {
            assert_eq!(ThreadMode::from_g_code(mode.g_code()), Ok(mode));
        }
    }

    #[test]
    fn errors_name_the_input() {
        use core::fmt::Write;
        let all = [
            ThreadError::PitchNotPositive,
            ThreadError::PitchTooCoarse,
            ThreadError::PitchTooFine,
            ThreadError::PitchOffGrid,
            ThreadError::UnknownMode,
            ThreadError::FeedLimitNotPositive,
        ];
        for e in all {
            let mut s: heapless::String<80> = heapless::String::new();
            assert!(write!(s, "{e}").is_ok());
            assert_eq!(s.as_str(), e.as_str());
            assert!(e.as_str().contains(": "));
        }
    }
}
