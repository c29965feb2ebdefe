//! [`Timestamp`]: a UTC instant in whole milliseconds, read and written as RFC 3339, with no
//! time crate (the civil-date arithmetic is Howard Hinnant's `days_from_civil`).

use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::fmt;

/// A UTC instant, milliseconds since 1970-01-01T00:00:00Z, between the years 0000 and 9999.
///
/// ```
/// use skyplan_airspace::Timestamp;
/// let t: Timestamp = "2026-03-01T12:00:00.5+01:00".parse()?;
/// assert_eq!(t.to_string(), "2026-03-01T11:00:00.500Z");
/// assert_eq!(t.plus_ms(500).to_string(), "2026-03-01T11:00:01Z");
/// assert!("2026-02-29T00:00:00Z".parse::<Timestamp>().is_err()); // not a leap year
/// # Ok::<(), skyplan_airspace::TimeError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Timestamp {
    ms: i64,
}

/// Why a text is not an RFC 3339 date-time.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{text:?} is not an RFC 3339 date-time (like 2026-03-01T12:00:00Z): {why}")]
pub struct TimeError {
    /// The text given (at most 64 characters of it).
    pub text: String,
    /// What is wrong.
    pub why: &'static str,
}

use skyplan_map::civil::{civil_from_days, days_from_civil};

fn days_in_month(y: i64, m: i64) -> i64 {
    match m {
        2 if (y % 4 == 0 && y % 100 != 0) || y % 400 == 0 => 29,
        2 => 28,
        4 | 6 | 9 | 11 => 30,
        _ => 31,
    }
}

const MS_PER_DAY: i64 = 86_400_000;

impl Timestamp {
    /// The earliest instant: 0000-01-01T00:00:00Z.
    pub const MIN: Timestamp = Timestamp {
        ms: -62_167_219_200_000,
    };
    /// The latest instant: 9999-12-31T23:59:59.999Z.
    pub const MAX: Timestamp = Timestamp {
        ms: 253_402_300_799_999,
    };

    /// The instant `ms` milliseconds after 1970-01-01T00:00:00Z, clamped to [`Self::MIN`,
    /// `Self::MAX`].
    pub fn from_unix_ms(ms: i64) -> Self {
        Self {
            ms: ms.clamp(Self::MIN.ms, Self::MAX.ms),
        }
    }

    /// Milliseconds since 1970-01-01T00:00:00Z.
    pub fn unix_ms(self) -> i64 {
        self.ms
    }

    /// The system clock now (whole milliseconds, rounded down).
    pub fn now() -> Self {
        let ms = match std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH) {
            Ok(d) => i64::try_from(d.as_millis()).unwrap_or(i64::MAX),
            Err(e) => -i64::try_from(e.duration().as_millis()).unwrap_or(i64::MAX),
        };
        Self::from_unix_ms(ms)
    }

    /// This instant moved by `ms` milliseconds (clamped to the representable range).
    pub fn plus_ms(self, ms: i64) -> Self {
        Self::from_unix_ms(self.ms.saturating_add(ms))
    }

    /// Milliseconds from `earlier` to `self`.
    pub fn ms_since(self, earlier: Timestamp) -> i64 {
        self.ms - earlier.ms
    }

    /// Reads an RFC 3339 date-time (`T` or `t` or a space between date and time, a fraction of
    /// any length — digits past milliseconds are dropped, rounding down — and `Z`, `z` or a
    /// `±hh:mm` offset). Leap seconds (`:60`) are refused.
    pub fn parse_rfc3339(text: &str) -> Result<Self, TimeError> {
        let fail = |why| TimeError {
            text: text.chars().take(64).collect(),
            why,
        };
        let b = text.as_bytes();
        let num = |from: usize, len: usize| -> Result<i64, TimeError> {
            let digits = b.get(from..from + len).ok_or(fail("too short"))?;
            if !digits.iter().all(u8::is_ascii_digit) {
                return Err(fail("expected digits in YYYY-MM-DDThh:mm:ss"));
            }
            Ok(digits
                .iter()
                .fold(0, |acc, &c| acc * 10 + i64::from(c - b'0')))
        };
        let sep = |at: usize, ok: &[u8]| -> Result<(), TimeError> {
            match b.get(at) {
                Some(c) if ok.contains(c) => Ok(()),
                _ => Err(fail("expected YYYY-MM-DDThh:mm:ss followed by Z or ±hh:mm")),
            }
        };
        let year = num(0, 4)?;
        sep(4, b"-")?;
        let month = num(5, 2)?;
        sep(7, b"-")?;
        let day = num(8, 2)?;
        sep(10, b"Tt ")?;
        let hour = num(11, 2)?;
        sep(13, b":")?;
        let minute = num(14, 2)?;
        sep(16, b":")?;
        let second = num(17, 2)?;
        if !(1..=12).contains(&month) {
            return Err(fail("month out of 01..12"));
        }
        if day < 1 || day > days_in_month(year, month) {
            return Err(fail("no such day in that month"));
        }
        if hour > 23 || minute > 59 {
            return Err(fail("hour or minute out of range"));
        }
        if second > 59 {
            return Err(fail("second out of 00..59 (leap seconds are not taken)"));
        }
        let mut at = 19;
        let mut ms = 0;
        if b.get(at) == Some(&b'.') {
            at += 1;
            let start = at;
            while b.get(at).is_some_and(u8::is_ascii_digit) {
                if at - start < 3 {
                    ms = ms * 10 + i64::from(b[at] - b'0');
                }
                at += 1;
            }
            if at == start {
                return Err(fail("a '.' without fraction digits"));
            }
            for _ in (at - start)..3 {
                ms *= 10;
            }
        }
        let offset_min = match b.get(at) {
            Some(b'Z' | b'z') => {
                at += 1;
                0
            }
            Some(&c @ (b'+' | b'-')) => {
                let h = num(at + 1, 2)?;
                sep(at + 3, b":")?;
                let m = num(at + 4, 2)?;
                if h > 23 || m > 59 {
                    return Err(fail("offset out of range"));
                }
                at += 6;
                if c == b'+' { h * 60 + m } else { -(h * 60 + m) }
            }
            _ => return Err(fail("missing the offset: Z or ±hh:mm")),
        };
        if at != b.len() {
            return Err(fail("unexpected text after the date-time"));
        }
        let local = days_from_civil(year, month, day) * MS_PER_DAY
            + ((hour * 60 + minute) * 60 + second) * 1000
            + ms;
        let utc = local - offset_min * 60_000;
        if !(Self::MIN.ms..=Self::MAX.ms).contains(&utc) {
            return Err(fail("outside the years 0000 to 9999 in UTC"));
        }
        Ok(Self { ms: utc })
    }
}

impl std::str::FromStr for Timestamp {
    type Err = TimeError;
    fn from_str(s: &str) -> Result<Self, TimeError> {
        Self::parse_rfc3339(s)
    }
}

impl fmt::Display for Timestamp {
    /// `YYYY-MM-DDThh:mm:ssZ`, with `.mmm` before the `Z` when the milliseconds are not 0.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let days = self.ms.div_euclid(MS_PER_DAY);
        let in_day = self.ms.rem_euclid(MS_PER_DAY);
        let (y, mo, d) = civil_from_days(days);
        let (s, ms) = (in_day / 1000, in_day % 1000);
        write!(
            f,
            "{y:04}-{mo:02}-{d:02}T{:02}:{:02}:{:02}",
            s / 3600,
            s / 60 % 60,
            s % 60
        )?;
        if ms != 0 {
            write!(f, ".{ms:03}")?;
        }
        f.write_str("Z")
    }
}

impl Serialize for Timestamp {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl<'de> Deserialize<'de> for Timestamp {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let text = String::deserialize(d)?;
        text.parse().map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn known_instants() {
        let t = |s: &str| s.parse::<Timestamp>().map(Timestamp::unix_ms);
        assert_eq!(t("1970-01-01T00:00:00Z"), Ok(0));
        // date -u -d 2026-03-01T12:34:56Z +%s → 1772368496
        assert_eq!(t("2026-03-01T12:34:56Z"), Ok(1_772_368_496_000));
        assert_eq!(t("2000-02-29t23:59:59.9999z"), Ok(951_868_799_999));
        assert_eq!(t("1969-12-31T23:59:59.001Z"), Ok(-999));
        assert_eq!(t("1970-01-01T01:00:00+01:00"), Ok(0));
        assert_eq!(t("1969-12-31T19:30:00-04:30"), Ok(0));
        assert_eq!(t("0000-01-01T00:00:00Z"), Ok(Timestamp::MIN.unix_ms()));
        assert_eq!(t("9999-12-31T23:59:59.999Z"), Ok(Timestamp::MAX.unix_ms()));
        for bad in [
            "",
            "2026-03-01",
            "2026-03-01T12:00:00",
            "2026-13-01T00:00:00Z",
            "2026-04-31T00:00:00Z",
            "1900-02-29T00:00:00Z",
            "2026-03-01T24:00:00Z",
            "2026-03-01T12:00:60Z",
            "2026-03-01T12:00:00.Z",
            "2026-03-01T12:00:00Zjunk",
            "2026-03-01T12:00:00+1:00",
            "0000-01-01T00:00:00+00:01",
            "２026-03-01T12:00:00Z",
        ] {
            assert!(t(bad).is_err(), "{bad:?} was taken");
        }
        assert_eq!(
            Timestamp::from_unix_ms(-999).to_string(),
            "1969-12-31T23:59:59.001Z"
        );
    }

    proptest! {
        #[test]
        fn written_text_reads_back(ms in Timestamp::MIN.unix_ms()..=Timestamp::MAX.unix_ms()) {
            let t = Timestamp::from_unix_ms(ms);
            prop_assert_eq!(t.to_string().parse::<Timestamp>(), Ok(t));
        }

        #[test]
        fn civil_dates_round_trip(days in -800_000i64..3_000_000) {
            let (y, m, d) = civil_from_days(days);
            prop_assert!((1..=12).contains(&m) && d >= 1 && d <= days_in_month(y, m));
            prop_assert_eq!(days_from_civil(y, m, d), days);
        }

        #[test]
        fn any_text_is_an_error_or_an_instant(s in "\\PC{0,40}") {
            let _ = s.parse::<Timestamp>();
        }
    }
}
