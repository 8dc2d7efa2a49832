//! The table machinery: [`param_struct!`] declares one part of the parameter set (struct, typed
//! getters, [`ParamSpec`](super::ParamSpec) table, by-name read and write) from one entry per
//! parameter; [`profile_part!`] adds read-through getters on [`Params`](super::Params).

/// Declares one part of the parameter set: a struct with one private field per parameter, its
/// typed getters, its [`ParamSpec`] table and by-name read/write. Adding a parameter is one
/// entry here (section, unit, writer, name, type, default, range check); the profile, the CLI and the DRO views follow.
macro_rules! param_struct {
    (
        $(#[doc = $sdoc:literal])+
        $Struct:ident ($access:ident) {
            $(
                $(#[doc = $doc:literal])+
                ($section:ident, $unit:literal, $writer:literal) $field:ident : $ty:ty => $ret:ty = $default:expr, $name:literal, $check:expr;
            )*
        }
    ) => {
        $(#[doc = $sdoc])+
        #[derive(Debug, Clone, PartialEq)]
        pub struct $Struct {
            $( pub(crate) $field: $ty, )*
        }

        impl Default for $Struct {
            fn default() -> Self {
                $Struct { $( $field: $default, )* }
            }
        }

        impl $Struct {
            $(
                $(#[doc = $doc])+
                #[must_use]
                pub fn $field(&self) -> $ret {
                    $crate::params::typed::ParamType::out(&self.$field)
                }
            )*

            /// This part's parameters, in the manual's order.
            pub const SPECS: &'static [$crate::params::ParamSpec] = &[$(
                $crate::params::ParamSpec {
                    name: $name,
                    kind: <$ty as $crate::params::typed::ParamType>::KIND,
                    access: $crate::params::Access::$access,
                    section: $crate::params::Section::$section,
                    doc: concat!($($doc),+),
                    unit: $unit,
                    range: { let check: $crate::params::checks::Check<$ty> = $check; check.range },
                    writer: $writer,
                },
            )*];

            /// Reads parameter `name` (case-insensitive); `None` when it is not in this part.
            #[must_use]
            pub fn get(&self, name: &str) -> Option<$crate::params::ParamValue> {
                $( if name.eq_ignore_ascii_case($name) { return Some($crate::params::typed::ParamType::to_value(&self.$field)); } )*
                None
            }

            /// Sets `name` (case-insensitive) to `value` after type and range checks; `Ok(false)`
            /// when `name` is not in this part. Access is the caller's business.
            // `expect` would be unfulfilled in the tables that are written by name.
            #[expect(clippy::allow_attributes, reason = "dead in one expansion of the macro only")]
            #[allow(dead_code, reason = "telemetry is never written by name")]
            pub(crate) fn set_raw(&mut self, name: &str, value: &$crate::params::ParamValue) -> Result<bool, $crate::VisionError> {
                $(
                    if name.eq_ignore_ascii_case($name) {
                        let invalid = |reason: String| $crate::VisionError::InvalidParam {
                            name: $name.to_string(),
                            value: value.to_string(),
                            reason,
                        };
                        let v = <$ty as $crate::params::typed::ParamType>::from_value(value)
                            .ok_or_else(|| invalid($crate::params::typed::kind_reason(<$ty as $crate::params::typed::ParamType>::KIND)))?;
                        let check: $crate::params::checks::Check<$ty> = $check;
                        check.check(&v).map_err(invalid)?;
                        self.$field = v;
                        return Ok(true);
                    }
                )*
                Ok(false)
            }
        }
    };
}

/// A persisted part of [`Params`]: [`param_struct!`] plus getters on [`Params`] that read
/// through to the part (one value, two ways to name the reader).
macro_rules! profile_part {
    ($(#[doc = $sdoc:literal])+ $Struct:ident in $via:ident { $($body:tt)* }) => {
        param_struct! { $(#[doc = $sdoc])+ $Struct (Config) { $($body)* } }
        profile_part!(@getters $via { $($body)* });
    };
    (@getters $via:ident {
        $(
            $(#[doc = $doc:literal])+
            ($section:ident, $unit:literal, $writer:literal) $field:ident : $ty:ty => $ret:ty = $default:expr, $name:literal, $check:expr;
        )*
    }) => {
        impl $crate::params::Params {
            $(
                $(#[doc = $doc])+
                #[must_use]
                pub fn $field(&self) -> $ret {
                    self.$via.$field()
                }
            )*
        }
    };
}
