//! What Grbl's numbered answers mean: the texts of Grbl 1.1's `error:N` and `ALARM:N` codes
//! (gnea/grbl `doc/csv/error_codes_en_US.csv` and `alarm_codes_en_US.csv`), for messages an
//! operator can act on without looking the number up.

/// The meaning of `error:code`, when Grbl 1.1 defines it.
#[must_use]
pub fn error_text(code: u8) -> Option<&'static str> {
    Some(match code {
        1 => "G-code words consist of a letter and a value; the letter was not found",
        2 => "a numeric value is missing or malformed",
        3 => "Grbl '$' system command was not recognized or supported",
        4 => "a negative value was given for an expected positive value",
        5 => "homing is not enabled in the settings",
        6 => "the minimum step pulse time must be greater than 3 usec",
        7 => "an EEPROM read failed; the affected values were restored to defaults",
        8 => "a '$' command needs the controller idle",
        9 => "G-code is locked out during an alarm or a jog",
        10 => "soft limits need homing enabled",
        11 => "the line has more characters than the controller accepts",
        12 => "the '$' setting would exceed the maximum step rate",
        13 => "the safety door is open",
        14 => "the build info or a startup line is too long for EEPROM",
        15 => "the jog target is beyond the machine's travel",
        16 => "the jog command has no '=' or contains a prohibited G-code",
        17 => "laser mode needs PWM output",
        20 => "unsupported or invalid G-code command",
        21 => "more than one G-code command from the same modal group",
        22 => "the feed rate is not set",
        23 => "the G-code command needs an integer value",
        24 => "two G-code commands that both need axis words",
        25 => "a G-code word is repeated in the line",
        26 => "no axis words in a command that needs them",
        27 => "invalid line number",
        28 => "the G-code command is missing a required value word",
        29 => "G59.x work coordinate systems are not supported",
        30 => "G53 is only allowed with G0 and G1",
        31 => "axis words in a line where no command uses them",
        32 => "G2 and G3 arcs need at least one in-plane axis word",
        33 => "the motion target is invalid (an arc whose start and end radii differ)",
        34 => "invalid arc radius",
        35 => "G2 and G3 arcs need at least one in-plane offset word",
        36 => "unused value words in the line",
        37 => "the G43.1 tool length offset is not on the tool length axis",
        38 => "the tool number is above the largest supported",
        _ => return None,
    })
}

/// The meaning of `ALARM:code`, when Grbl 1.1 defines it.
#[must_use]
pub fn alarm_text(code: u8) -> Option<&'static str> {
    Some(match code {
        1 => "hard limit triggered; the position is likely lost, re-home",
        2 => "soft limit: the motion target exceeds the machine's travel",
        3 => "reset while in motion; the position is likely lost, re-home",
        4 => "probe fail: the probe was not in the expected state before the cycle",
        5 => "probe fail: the probe did not touch within the travel",
        6 => "homing fail: reset during the homing cycle",
        7 => "homing fail: the safety door was opened during homing",
        8 => "homing fail: the pull-off did not clear the limit switch",
        9 => "homing fail: the limit switch was not found",
        _ => return None,
    })
}

/// `error:code` with its meaning, e.g. `error:20 (unsupported or invalid G-code command)`.
#[must_use]
pub fn describe_error(code: u8) -> String {
    error_text(code).map_or_else(|| format!("error:{code}"), |t| format!("error:{code} ({t})"))
}

/// `ALARM:code` with its meaning.
#[must_use]
pub fn describe_alarm(code: u8) -> String {
    alarm_text(code).map_or_else(|| format!("ALARM:{code}"), |t| format!("ALARM:{code} ({t})"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_code_grbl_defines_has_a_text_and_others_only_their_number() {
        let errors: Vec<u8> = (0..=u8::MAX).filter(|&c| error_text(c).is_some()).collect();
        let expected: Vec<u8> = (1..=17).chain(20..=38).collect();
        assert_eq!(errors, expected);
        let alarms: Vec<u8> = (0..=u8::MAX).filter(|&c| alarm_text(c).is_some()).collect();
        assert_eq!(alarms, (1..=9).collect::<Vec<u8>>());
        assert_eq!(describe_error(20), "error:20 (unsupported or invalid G-code command)");
        assert_eq!(describe_error(18), "error:18");
        assert_eq!(describe_alarm(3), "ALARM:3 (reset while in motion; the position is likely lost, re-home)");
        assert_eq!(describe_alarm(200), "ALARM:200");
    }
}
