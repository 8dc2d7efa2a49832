//! How the report types serialize the `vision-math` values they hold (`vision-math` stays free
//! of serde). Points and vectors are `[x, y]`, matrices are rows `[[m11, m12], [m21, m22]]`,
//! units are `"in"` / `"mm"`. The README's "JSON output of `run --json`" documents the result.

use serde::ser::{SerializeMap, SerializeStruct};
use serde::{Serialize, Serializer};
use vision_math::{AlignmentChain, Fit, LengthUnit, Matrix2, Point2, Remap, Vector2};

use crate::controller::{AppliedBy, HowApplied, WorkRotation};
use crate::driver::Judgment;
use crate::params::ParamValue;

/// `[x, y]`.
pub(crate) fn point<S: Serializer>(p: &Point2<f64>, s: S) -> Result<S::Ok, S::Error> {
    [p.x, p.y].serialize(s)
}

/// `[x, y]`.
pub(crate) fn vector<S: Serializer>(v: &Vector2<f64>, s: S) -> Result<S::Ok, S::Error> {
    [v.x, v.y].serialize(s)
}

/// `[[x, y], …]`.
pub(crate) fn vectors<S: Serializer>(v: &[Vector2<f64>], s: S) -> Result<S::Ok, S::Error> {
    s.collect_seq(v.iter().map(|v| [v.x, v.y]))
}

/// Rows: `[[m11, m12], [m21, m22]]`.
pub(crate) fn matrix<S: Serializer>(m: &Matrix2<f64>, s: S) -> Result<S::Ok, S::Error> {
    [[m[(0, 0)], m[(0, 1)]], [m[(1, 0)], m[(1, 1)]]].serialize(s)
}

/// `"in"` or `"mm"`.
#[expect(clippy::trivially_copy_pass_by_ref, reason = "serde's `serialize_with` passes a reference")]
pub(crate) fn unit<S: Serializer>(u: &LengthUnit, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(u.short_name())
}

/// `"OK"`, `"NG"` or `"unknown"`: the judgment's label.
#[expect(clippy::trivially_copy_pass_by_ref, reason = "serde's `serialize_with` passes a reference")]
pub(crate) fn judgment<S: Serializer>(j: &Judgment, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(j.label())
}

/// `{ swap_xy, invert_x, invert_y }`.
#[expect(clippy::trivially_copy_pass_by_ref, reason = "serde's `serialize_with` passes a reference")]
pub(crate) fn remap<S: Serializer>(r: &Remap, s: S) -> Result<S::Ok, S::Error> {
    let mut st = s.serialize_struct("Remap", 3)?;
    st.serialize_field("swap_xy", &r.swap_xy)?;
    st.serialize_field("invert_x", &r.invert_x)?;
    st.serialize_field("invert_y", &r.invert_y)?;
    st.end()
}

/// `{ shift, center, rotation_deg, scale }`: the G52 / G68 / G51 values.
pub(crate) fn chain<S: Serializer>(c: &AlignmentChain, s: S) -> Result<S::Ok, S::Error> {
    let mut st = s.serialize_struct("AlignmentChain", 4)?;
    st.serialize_field("shift", &[c.shift.x, c.shift.y])?;
    st.serialize_field("center", &[c.center.x, c.center.y])?;
    st.serialize_field("rotation_deg", &c.rotation_deg)?;
    st.serialize_field("scale", &[c.scale.x, c.scale.y])?;
    st.end()
}

/// Nothing, or for a controller that rotates its work offset one entry named after it:
/// `{ rotation_deg, g52, base_rotation_deg, ignored_scale }` (M282's report, flattened).
impl Serialize for HowApplied {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        /// The entry's value.
        struct Entry<'a>(&'a WorkRotation, Vector2<f64>);
        impl Serialize for Entry<'_> {
            fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                let Entry(w, ignored) = self;
                let mut st = s.serialize_struct("WorkRotation", 4)?;
                st.serialize_field("rotation_deg", &w.rotation_deg)?;
                st.serialize_field("g52", &[w.shift.x, w.shift.y])?;
                st.serialize_field("base_rotation_deg", &w.base_rotation_deg)?;
                st.serialize_field("ignored_scale", &[ignored.x, ignored.y])?;
                st.end()
            }
        }
        let mut map = s.serialize_map(None)?;
        if let Some(w) = &self.work_rotation {
            let ignored = self.scale_left_out.map_or(Vector2::new(1.0, 1.0), |l| l.scale);
            map.serialize_entry(self.controller, &Entry(w, ignored))?;
        }
        if self.by == AppliedBy::Host {
            map.serialize_entry("applied_by", "host")?;
        }
        map.end()
    }
}

/// `{ model, rotation_deg, scale, shear, commanded_centroid, observed_centroid, len, rms,
/// max_residual }`.
pub(crate) fn fit<S: Serializer>(f: &Fit, s: S) -> Result<S::Ok, S::Error> {
    let t = &f.transform;
    let mut st = s.serialize_struct("Fit", 9)?;
    st.serialize_field("model", t.model.name())?;
    st.serialize_field("rotation_deg", &t.theta_deg())?;
    st.serialize_field("scale", &[t.scale.x, t.scale.y])?;
    st.serialize_field("shear", &t.shear)?;
    st.serialize_field("commanded_centroid", &[t.commanded_centroid.x, t.commanded_centroid.y])?;
    st.serialize_field("observed_centroid", &[t.observed_centroid.x, t.observed_centroid.y])?;
    st.serialize_field("len", &f.len)?;
    st.serialize_field("rms", &f.rms)?;
    st.serialize_field("max_residual", &f.max_residual)?;
    st.end()
}

impl Serialize for ParamValue {
    /// A JSON boolean, integer, number or string.
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            ParamValue::Bool(b) => s.serialize_bool(*b),
            ParamValue::Int(i) => s.serialize_i64(*i),
            ParamValue::Float(f) => s.serialize_f64(*f),
            ParamValue::Text(t) => s.serialize_str(t),
        }
    }
}

/// A map from each spec's manual name to its value, in the specs' order.
pub(crate) fn named_values<S: Serializer>(
    specs: &[crate::params::ParamSpec],
    get: impl Fn(&str) -> Option<ParamValue>,
    s: S,
) -> Result<S::Ok, S::Error> {
    let mut map = s.serialize_map(Some(specs.len()))?;
    for spec in specs {
        if let Some(v) = get(spec.name) {
            map.serialize_entry(spec.name, &v)?;
        }
    }
    map.end()
}
