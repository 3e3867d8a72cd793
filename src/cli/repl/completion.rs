//! Completion on the terminal: of commands, and of each command's
//! arguments as the command table says (states, parameters, `show` topics,
//! value names in conditions, file names (for `load` and `show tactile`)).

use cablecell::orchestrator::State;
use cablecell::orchestrator::breakpoint::RunValues;
use rustyline::Helper;
use rustyline::completion::{Completer, FilenameCompleter, Pair};
use rustyline::highlight::Highlighter;
use rustyline::hint::Hinter;
use rustyline::validate::Validator;

use super::commands::{COMMANDS, Completes, SHOW_TOPICS, find};
use super::session::Session;

/// Completion of commands, states, parameters, `show` topics, value
/// names in conditions, and file names for `load`.
pub(super) struct ReplHelper {
    params: Vec<String>,
    files: FilenameCompleter,
}

impl ReplHelper {
    pub(super) fn new(session: &Session) -> Self {
        Self {
            params: session
                .task
                .as_ref()
                .map(|t| t.params.names())
                .unwrap_or_default(),
            files: FilenameCompleter::new(),
        }
    }
}

impl Completer for ReplHelper {
    type Candidate = Pair;

    fn complete(
        &self,
        line: &str,
        pos: usize,
        ctx: &rustyline::Context<'_>,
    ) -> rustyline::Result<(usize, Vec<Pair>)> {
        let before = &line[..pos];
        let start = before.rfind(char::is_whitespace).map_or(0, |i| i + 1);
        let word = &before[start..];
        let words: Vec<&str> = before[..start].split_whitespace().collect();
        let names = || COMMANDS.iter().map(|spec| spec.name.to_owned()).collect();
        let candidates: Vec<String> = match words.as_slice() {
            [] => names(),
            [command, args @ ..] => match (find(command).map(|spec| spec.completes), args) {
                (Some(Completes::File), []) => return self.files.complete(line, pos, ctx),
                (Some(Completes::Breakpoint), []) => {
                    State::NAMES.iter().map(|s| (*s).to_owned()).collect()
                }
                (Some(Completes::Breakpoint), [_]) => vec!["if".to_owned()],
                (Some(Completes::Breakpoint), [_, "if", ..]) => RunValues::NAMES
                    .iter()
                    .map(|s| (*s).to_owned())
                    .chain(["abs(", "and", "or", "not"].map(str::to_owned))
                    .collect(),
                (Some(Completes::Topic), []) => {
                    SHOW_TOPICS.iter().map(|t| t.name.to_owned()).collect()
                }
                // A topic that takes a file: `show tactile FILE`.
                (Some(Completes::Topic), [topic])
                    if SHOW_TOPICS
                        .iter()
                        .any(|t| t.name == *topic && t.takes_file()) =>
                {
                    return self.files.complete(line, pos, ctx);
                }
                (Some(Completes::Param), []) => self.params.clone(),
                (Some(Completes::Command), []) => names(),
                _ => Vec::new(),
            },
        };
        let pairs = candidates
            .into_iter()
            .filter(|c| c.starts_with(word))
            .map(|c| Pair {
                // A finished word is followed by a space, ready for the next.
                replacement: if c.ends_with('(') {
                    c.clone()
                } else {
                    format!("{c} ")
                },
                display: c,
            })
            .collect();
        Ok((start, pairs))
    }
}

impl Hinter for ReplHelper {
    type Hint = String;
}

impl Highlighter for ReplHelper {}

impl Validator for ReplHelper {}

impl Helper for ReplHelper {}
