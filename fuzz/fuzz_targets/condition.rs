//! Breakpoint conditions as typed after `break STATE if`: a parsed
//! condition's text parses to the same condition, and it evaluates on a
//! run that has no values yet; an error points inside the text or just
//! past its end.

#![no_main]

use cablecell::orchestrator::breakpoint::{Condition, ConditionError, RunValues};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match Condition::parse(text) {
        Ok(condition) => {
            assert_eq!(Condition::parse(condition.text()), Ok(condition.clone()));
            let _ = condition.holds(&RunValues::default());
        }
        Err(
            ConditionError::Syntax { column, .. }
            | ConditionError::UnknownName { column, .. }
            | ConditionError::Type { column, .. },
        ) => assert!(
            (1..=text.chars().count() + 1).contains(&column),
            "column {column}"
        ),
        Err(_) => {}
    }
});
