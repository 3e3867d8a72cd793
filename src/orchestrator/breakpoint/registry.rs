//! The breakpoints of a session: set, listed, deleted, and hit as the
//! machine enters a state.

use super::condition::{Condition, ConditionError};
use super::values::RunValues;
use crate::orchestrator::machine::State;

/// A breakpoint could not be set.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum BreakpointError {
    /// No state of the machine has this name: use one of `known`.
    #[error("unknown state `{name}`; states: {}", State::NAMES.join(", "))]
    UnknownState { name: String },
    /// The condition after `if` does not parse.
    #[error("in the condition, {0}")]
    Condition(#[from] ConditionError),
}

/// Stop when the machine enters `state`, if `condition` holds then.
#[derive(Debug, Clone, PartialEq)]
pub struct Breakpoint {
    pub id: usize,
    pub state: &'static str,
    pub condition: Option<Condition>,
    /// How many times it has stopped the run.
    pub hits: usize,
}

impl std::fmt::Display for Breakpoint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.id, self.state)?;
        if let Some(condition) = &self.condition {
            write!(f, " if {}", condition.text())?;
        }
        write!(f, " (hit {} times)", self.hits)
    }
}

/// The breakpoints of a session, numbered from 1 in the order set.
#[derive(Debug, Clone, Default)]
pub struct Breakpoints {
    list: Vec<Breakpoint>,
    last_id: usize,
}

impl Breakpoints {
    /// Adds `break STATE [if CONDITION]`; returns its number.
    pub fn add(&mut self, state: &str, condition: Option<&str>) -> Result<usize, BreakpointError> {
        let state = State::named(state)
            .ok_or_else(|| BreakpointError::UnknownState {
                name: state.to_owned(),
            })?
            .name();
        let condition = condition.map(Condition::parse).transpose()?;
        self.last_id += 1;
        self.list.push(Breakpoint {
            id: self.last_id,
            state,
            condition,
            hits: 0,
        });
        Ok(self.last_id)
    }

    /// Removes breakpoint `id`; false if there is none.
    pub fn delete(&mut self, id: usize) -> bool {
        let before = self.list.len();
        self.list.retain(|b| b.id != id);
        self.list.len() < before
    }

    pub fn iter(&self) -> impl Iterator<Item = &Breakpoint> {
        self.list.iter()
    }

    /// The first breakpoint that fires on entering `state` with `values`,
    /// its hit counted.
    pub fn hit(&mut self, state: &str, values: &RunValues) -> Option<&Breakpoint> {
        let breakpoint = self
            .list
            .iter_mut()
            .find(|b| b.state == state && b.condition.as_ref().is_none_or(|c| c.holds(values)))?;
        breakpoint.hits += 1;
        Some(breakpoint)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn values(pairs: &[(&str, f64)]) -> RunValues {
        RunValues::with(pairs)
    }

    #[test]
    fn breakpoints_fire_by_state_and_condition() {
        let (regrasp, verify) = (State::Regrasp {}.name(), State::Verify {}.name());
        let mut breaks = Breakpoints::default();
        assert!(matches!(
            breaks.add("regraps", None),
            Err(BreakpointError::UnknownState { .. })
        ));
        let first = breaks.add(regrasp, Some("abs(n_mm) > 2")).unwrap();
        let second = breaks.add(verify, None).unwrap();
        assert_eq!((first, second), (1, 2));
        assert!(breaks.hit(regrasp, &values(&[("n_mm", 1.0)])).is_none());
        assert_eq!(
            breaks
                .hit(regrasp, &values(&[("n_mm", -2.2)]))
                .map(|b| b.id),
            Some(1)
        );
        assert_eq!(breaks.hit(verify, &values(&[])).map(|b| b.hits), Some(1));
        assert!(breaks.delete(1));
        assert!(!breaks.delete(1));
        assert!(breaks.hit(regrasp, &values(&[("n_mm", -2.2)])).is_none());
        assert_eq!(breaks.iter().count(), 1);
    }
}
