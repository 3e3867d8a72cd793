//! REPL input. The REPL's dispatch (a line's first word looked up in its
//! command table, in the binary) only splits the line into words; the
//! commands that parse their arguments hand them to the library, and that
//! is fuzzed here, the line split as the REPL splits it: `break STATE [if
//! EXPR]` sets a breakpoint, `set PARAM VALUE` changes a parameter of the
//! shipped task. A breakpoint set as listed sets the same again, and the
//! value `show params` lists is one `set` takes back unchanged.

#![no_main]

use std::path::Path;
use std::sync::LazyLock;

use cablecell::orchestrator::breakpoint::{Breakpoints, Condition};
use cablecell::orchestrator::params::TaskParams;
use libfuzzer_sys::fuzz_target;

static PARAMS: LazyLock<TaskParams> = LazyLock::new(|| {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../tasks/regrasp.toml");
    TaskParams::load(Path::new(path)).expect("the shipped task loads")
});

fuzz_target!(|data: &[u8]| {
    let Ok(line) = std::str::from_utf8(data) else {
        return;
    };
    let words: Vec<&str> = line.split_whitespace().collect();
    match words.as_slice() {
        ["break" | "b", state] => {
            let _ = Breakpoints::default().add(state, None);
        }
        ["break" | "b", state, "if", condition @ ..] if !condition.is_empty() => {
            let mut breakpoints = Breakpoints::default();
            if breakpoints.add(state, Some(&condition.join(" "))).is_err() {
                return;
            }
            let set = breakpoints.iter().next().expect("the breakpoint just set");
            let mut again = Breakpoints::default();
            again
                .add(set.state, set.condition.as_ref().map(Condition::text))
                .expect("a breakpoint as listed sets again");
            assert_eq!(again.iter().next(), Some(set));
        }
        ["set", param, value @ ..] if !value.is_empty() => {
            let mut params = PARAMS.clone();
            if params.set(param, &value.join(" ")).is_err() {
                return;
            }
            let listed = params.list();
            let (_, shown) = listed
                .iter()
                .find(|(name, _)| name == param)
                .expect("a parameter set is listed");
            let mut again = params.clone();
            again
                .set(param, shown)
                .expect("`set` takes what `show params` lists");
            assert_eq!(again.list(), listed);
        }
        _ => {}
    }
});
