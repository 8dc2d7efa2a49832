//! The Rust types a parameter can have, and how a [`ParamValue`] (what a profile, CLI or DRO
//! wrote) is read as each.

use vision_math::LengthUnit;

use super::value::{ParamKind, ParamValue};

/// A Rust type a parameter can have.
pub(crate) trait ParamType: Sized {
    type Out<'a>
    where
        Self: 'a;
    const KIND: ParamKind;
    fn out(&self) -> Self::Out<'_>;
    fn to_value(&self) -> ParamValue;
    fn from_value(v: &ParamValue) -> Option<Self>;
}

impl ParamType for bool {
    type Out<'a> = bool;
    const KIND: ParamKind = ParamKind::YesNo;
    fn out(&self) -> bool {
        *self
    }
    fn to_value(&self) -> ParamValue {
        ParamValue::Bool(*self)
    }
    fn from_value(v: &ParamValue) -> Option<Self> {
        match v {
            ParamValue::Bool(b) => Some(*b),
            ParamValue::Int(0) => Some(false),
            ParamValue::Int(1) => Some(true),
            ParamValue::Float(f) if *f == 0.0 => Some(false),
            ParamValue::Float(f) if (*f - 1.0).abs() < f64::EPSILON => Some(true),
            ParamValue::Text(s) => match s.trim().to_ascii_lowercase().as_str() {
                "yes" | "true" | "1" | "on" => Some(true),
                "no" | "false" | "0" | "off" => Some(false),
                _ => None,
            },
            _ => None,
        }
    }
}

impl ParamType for i64 {
    type Out<'a> = i64;
    const KIND: ParamKind = ParamKind::Integer;
    fn out(&self) -> i64 {
        *self
    }
    fn to_value(&self) -> ParamValue {
        ParamValue::Int(*self)
    }
    fn from_value(v: &ParamValue) -> Option<Self> {
        match v {
            ParamValue::Int(i) => Some(*i),
            #[expect(clippy::cast_possible_truncation, reason = "checked integral and in range")]
            ParamValue::Float(f) if f.fract() == 0.0 && f.abs() < 9.0e15 => Some(*f as i64),
            ParamValue::Text(s) => s.trim().parse().ok(),
            _ => None,
        }
    }
}

impl ParamType for f64 {
    type Out<'a> = f64;
    const KIND: ParamKind = ParamKind::Float;
    fn out(&self) -> f64 {
        *self
    }
    fn to_value(&self) -> ParamValue {
        ParamValue::Float(*self)
    }
    fn from_value(v: &ParamValue) -> Option<Self> {
        match v {
            ParamValue::Float(f) => Some(*f),
            ParamValue::Int(i) => Some(*i as f64),
            ParamValue::Text(s) => s.trim().parse().ok(),
            ParamValue::Bool(_) => None,
        }
    }
}

impl ParamType for String {
    type Out<'a> = &'a str;
    const KIND: ParamKind = ParamKind::Text;
    fn out(&self) -> &str {
        self
    }
    fn to_value(&self) -> ParamValue {
        ParamValue::Text(self.clone())
    }
    fn from_value(v: &ParamValue) -> Option<Self> {
        match v {
            ParamValue::Text(s) => Some(s.clone()),
            _ => None,
        }
    }
}

impl ParamType for LengthUnit {
    type Out<'a> = LengthUnit;
    const KIND: ParamKind = ParamKind::Choice(&["in", "mm"]);
    fn out(&self) -> LengthUnit {
        *self
    }
    fn to_value(&self) -> ParamValue {
        ParamValue::Text(self.short_name().to_string())
    }
    fn from_value(v: &ParamValue) -> Option<Self> {
        match v {
            ParamValue::Text(s) => match s.trim().to_ascii_lowercase().as_str() {
                "in" | "inch" | "inches" => Some(LengthUnit::Inch),
                "mm" | "millimetre" | "millimeter" => Some(LengthUnit::Millimetre),
                _ => None,
            },
            _ => None,
        }
    }
}

/// `v` read as a value of `kind` (text is read as the kind, as [`ParamType::from_value`] does;
/// a choice matches its words case-insensitively and gives the word as declared); `None` when
/// `v` is not one.
pub(crate) fn coerce(kind: ParamKind, v: &ParamValue) -> Option<ParamValue> {
    match kind {
        ParamKind::YesNo => bool::from_value(v).map(ParamValue::Bool),
        ParamKind::Integer => i64::from_value(v).map(ParamValue::Int),
        ParamKind::Float => f64::from_value(v).map(ParamValue::Float),
        ParamKind::Text => String::from_value(v).map(ParamValue::Text),
        ParamKind::Choice(words) => match v {
            ParamValue::Text(s) => {
                words.iter().find(|w| w.eq_ignore_ascii_case(s.trim())).map(|w| ParamValue::Text((*w).to_string()))
            }
            _ => None,
        },
    }
}

/// Why a value is not of `kind`, for [`crate::VisionError::InvalidParam`].
pub(crate) fn kind_reason(kind: ParamKind) -> String {
    match kind {
        ParamKind::YesNo => "must be Yes or No".into(),
        ParamKind::Integer => "must be an integer".into(),
        ParamKind::Float => "must be a number".into(),
        ParamKind::Text => "must be text".into(),
        ParamKind::Choice(words) => format!("must be one of {}", words.join(", ")),
    }
}
