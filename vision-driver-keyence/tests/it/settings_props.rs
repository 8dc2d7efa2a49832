//! The driver's settings (`[keyence]`): every value the driver accepts is read back as the
//! same configuration, by name, through a profile file and in the manual's flat form; every
//! value it refuses is refused naming the setting, and changes nothing.

use std::time::Duration;

use proptest::prelude::*;
use vision_core::profile::{from_toml_with, to_toml};
use vision_core::{DriverRegistry, ParamValue, Params, VisionError};
use vision_driver_keyence::{register, settings, KeyenceConfig};

fn base() -> Params {
    let mut registry = DriverRegistry::new();
    register(&mut registry);
    registry.params()
}

/// Sets `name`, then checks it was refused naming it and left as it was.
fn refused(name: &str, value: ParamValue) -> Result<(), TestCaseError> {
    let mut p = base();
    let before = p.get(name).map_err(|e| TestCaseError::fail(e.to_string()))?;
    match p.set(name, value.clone()) {
        Err(VisionError::InvalidParam { name: n, .. }) => prop_assert_eq!(n, name),
        other => prop_assert!(false, "{name} = {value}: {other:?}"),
    }
    prop_assert_eq!(p.get(name).ok(), Some(before));
    // A profile that says so is refused too, naming it.
    let text = format!("[keyence]\n{name} = {}\n", toml_text(&value));
    let e = from_toml_with(&format!("[vision]\n{text}"), base()).expect_err("refused");
    prop_assert!(e.contains(name), "{}", e);
    Ok(())
}

fn toml_text(v: &ParamValue) -> String {
    match v {
        ParamValue::Bool(b) => b.to_string(),
        ParamValue::Int(i) => i.to_string(),
        ParamValue::Float(f) if f.is_nan() => "nan".into(),
        ParamValue::Float(f) if f.is_infinite() => (if *f > 0.0 { "inf" } else { "-inf" }).into(),
        ParamValue::Float(f) => format!("{f:?}"),
        ParamValue::Text(s) => format!("{s:?}"),
    }
}

/// A host name the driver accepts: labels of letters, digits and `-`, not starting with `-`.
fn host_name() -> impl Strategy<Value = String> {
    "[a-z0-9][a-z0-9-]{0,12}(\\.[a-z0-9-]{1,12}){0,3}"
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// Good values: by name (typed or as text), in `[keyence]` or in `[vision]`, the driver's
    /// configuration is the values set, and a save and a load give back the same parameters.
    #[test]
    fn accepted_settings_reach_the_driver_and_survive_the_profile(
        ip in prop_oneof![
            any::<[u8; 4]>().prop_map(|o| std::net::Ipv4Addr::from(o).to_string()),
            any::<[u16; 8]>().prop_map(|o| std::net::Ipv6Addr::from(o).to_string()),
            host_name(),
        ],
        port in 1u16..=65535,
        timeout_ms in 1u64..=300_000,
        grab_ms in 0u64..=60_000,
        dir in "[A-Za-z0-9_ /.-]{0,40}",
        as_text in any::<bool>(),
        flat in any::<bool>(),
    ) {
        let timeout = timeout_ms as f64 / 1000.0;
        let grab = grab_ms as f64 / 1000.0;
        let mut p = base();
        let number = |v: ParamValue| if as_text { ParamValue::Text(toml_text(&v)) } else { v };
        p.set("VisionIP", ip.as_str()).map_err(|e| TestCaseError::fail(e.to_string()))?;
        p.set("visionport", number(ParamValue::Int(i64::from(port)))).map_err(|e| TestCaseError::fail(e.to_string()))?;
        p.set("VisionTimeout", number(ParamValue::Float(timeout))).map_err(|e| TestCaseError::fail(e.to_string()))?;
        p.set("VisionImageGrabTimeout", number(ParamValue::Float(grab))).map_err(|e| TestCaseError::fail(e.to_string()))?;
        p.set("VisionImageWatchDir", dir.as_str()).map_err(|e| TestCaseError::fail(e.to_string()))?;

        let c = KeyenceConfig::from_params(&p).map_err(|e| TestCaseError::fail(e.to_string()))?;
        prop_assert_eq!(&c.ip, &ip);
        prop_assert_eq!(c.port, port);
        prop_assert_eq!(c.timeout, Duration::from_secs_f64(timeout));
        prop_assert_eq!(c.images.timeout, Duration::from_secs_f64(grab));
        prop_assert_eq!(c.images.dir.to_string_lossy(), dir.as_str());
        prop_assert_eq!(p.get("VisionPort").ok(), Some(ParamValue::Int(i64::from(port))));

        // Saved under [keyence]; the manual's flat form (in [vision]) loads the same.
        let text = to_toml(&p).map_err(TestCaseError::fail)?;
        let table = &text[text.find("[keyence]").expect("a [keyence] table")..];
        prop_assert!(table.contains(&format!("VisionPort = {port}\n")), "{}", text);
        let text = if flat { text.replace("\n[keyence]\n", "\n") } else { text };
        let back = from_toml_with(&text, base()).map_err(|e| TestCaseError::fail(format!("{e}\n{text}")))?;
        prop_assert_eq!(&back, &p);
        prop_assert_eq!(KeyenceConfig::from_params(&back).ok(), Some(c));
    }

    #[test]
    fn a_port_outside_1_to_65535_is_refused(port in prop_oneof![i64::MIN..=0, 65_536..=i64::MAX]) {
        refused("VisionPort", ParamValue::Int(port))?;
    }

    #[test]
    fn a_timeout_outside_0_to_300_s_is_refused(
        t in prop_oneof![
            -1e9..=0.0f64,
            300.000_001..1e12f64,
            Just(f64::NAN),
            Just(f64::INFINITY),
        ],
    ) {
        refused("VisionTimeout", ParamValue::Float(t))?;
    }

    #[test]
    fn a_grab_timeout_outside_0_to_60_s_is_refused(
        t in prop_oneof![-1e9..-1e-9f64, 60.000_001..1e12f64, Just(f64::NAN)],
    ) {
        refused("VisionImageGrabTimeout", ParamValue::Float(t))?;
    }

    #[test]
    fn an_address_with_other_characters_is_refused(
        ip in "[a-z0-9.-]{0,8}[ !@#$%^&*()_+=,;:/?<>\\[\\]{}|~][a-z0-9.-]{0,8}",
    ) {
        prop_assume!(ip.parse::<std::net::IpAddr>().is_err());
        refused("VisionIP", ParamValue::Text(ip))?;
    }

    #[test]
    fn a_number_for_the_address_or_text_for_the_port_is_refused(n in any::<i64>(), word in "[a-z]{1,8}") {
        refused("VisionIP", ParamValue::Int(n))?;
        refused("VisionPort", ParamValue::Text(word))?;
    }
}

#[test]
fn the_defaults_are_the_manuals_and_the_table_is_keyence() {
    let p = base();
    let c = KeyenceConfig::from_params(&p).expect("defaults");
    assert_eq!((c.ip.as_str(), c.port, c.timeout), ("192.168.208.80", 8500, Duration::from_secs(3)));
    assert_eq!(c.images.timeout, Duration::from_secs(2));
    assert!(c.images.dir.as_os_str().is_empty());
    assert_eq!(KeyenceConfig::from_params(&Params::default()).ok(), Some(c), "no table: the defaults");
    assert_eq!(settings::SETTINGS.table, "keyence");
    let names: Vec<_> = settings::SETTINGS.settings.iter().map(|s| s.spec.name).collect();
    assert_eq!(names, ["VisionIP", "VisionPort", "VisionTimeout", "VisionImageWatchDir", "VisionImageGrabTimeout"]);
}
