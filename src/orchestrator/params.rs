//! A task's parameters as the REPL's `show params` and `set` see them: the
//! task file's values by dotted name (`tolerance.n_mm`), each change
//! checked exactly as the task file is, so a value the file would refuse
//! is refused with the same message.

use std::path::{Path, PathBuf};

use crate::cell::CellFile;
use crate::schema::toml_file::{ConfigError, parse, read};
use crate::task::{TaskFile, check_on_cell, parse_task};

/// Why a parameter could not be set.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ParamError {
    /// No parameter of the task has this name: use one of `known`.
    #[error("unknown parameter `{name}`; parameters: {}", known.join(", "))]
    Unknown { name: String, known: Vec<String> },
    /// The value is not a TOML value, or the task file would refuse it:
    /// `message` says what is expected.
    #[error("{name}: {message}")]
    Invalid { name: String, message: String },
}

/// A task file's values, changeable one at a time.
#[derive(Debug, Clone)]
pub struct TaskParams {
    path: PathBuf,
    table: toml::Table,
    task: TaskFile,
    /// The cell the task runs on, with its file, whose limits a value
    /// must also keep (`check_on_cell`).
    cell: Option<(PathBuf, CellFile)>,
}

impl TaskParams {
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        Self::load_with(path, None)
    }

    /// The task file at `path` for the cell `cell` (read from `cell_path`):
    /// a value beyond the cell's limits is refused at load and by `set`.
    pub fn load_on_cell(
        path: &Path,
        cell_path: &Path,
        cell: &CellFile,
    ) -> Result<Self, ConfigError> {
        Self::load_with(path, Some((cell_path.to_owned(), cell.clone())))
    }

    fn load_with(path: &Path, cell: Option<(PathBuf, CellFile)>) -> Result<Self, ConfigError> {
        let text = read(path)?;
        let task = parse_task(path, &text)?;
        if let Some((cell_path, cell)) = &cell {
            check_on_cell(path, &text, &task, cell_path, cell)?;
        }
        let mut table: toml::Table = parse(path, &text)?;
        // Optional values with a default are parameters too, at the value
        // the task file's loader gave them.
        if let Some(toml::Value::Table(regrasp)) = table.get_mut("regrasp") {
            regrasp.entry("correction_gain").or_insert_with(|| {
                toml::Value::try_from(task.regrasp.correction_gain)
                    .expect("a correction gain, two numbers, is a TOML table")
            });
        }
        Ok(Self {
            path: path.to_owned(),
            table,
            task,
            cell,
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    pub fn task(&self) -> &TaskFile {
        &self.task
    }

    /// Every parameter with its value, in file order (`[task]`, which
    /// names the task, is not a parameter).
    pub fn list(&self) -> Vec<(String, String)> {
        let mut out = Vec::new();
        for (key, value) in self.table.iter().filter(|(key, _)| *key != "task") {
            leaves(key, value, &mut out);
        }
        out
    }

    pub fn names(&self) -> Vec<String> {
        self.list().into_iter().map(|(name, _)| name).collect()
    }

    /// Sets `name` to `value` (TOML: `0.5`, `"ridge"`, or a bare word taken
    /// as a string), if the task file would accept it.
    pub fn set(&mut self, name: &str, value: &str) -> Result<(), ParamError> {
        if !self.names().iter().any(|n| n == name) {
            return Err(ParamError::Unknown {
                name: name.to_owned(),
                known: self.names(),
            });
        }
        let invalid = |message: String| ParamError::Invalid {
            name: name.to_owned(),
            message,
        };
        let value = parse_value(value).map_err(invalid)?;
        let mut table = self.table.clone();
        let mut slot = &mut table;
        let mut keys = name.split('.').peekable();
        while let Some(key) = keys.next() {
            if keys.peek().is_none() {
                slot.insert(key.to_owned(), value.clone());
                break;
            }
            match slot.get_mut(key) {
                Some(toml::Value::Table(inner)) => slot = inner,
                _ => return Err(invalid("not a value".into())),
            }
        }
        let text = toml::to_string(&table).map_err(|e| invalid(e.to_string()))?;
        let checked = parse_task(&self.path, &text).and_then(|task| match &self.cell {
            Some((cell_path, cell)) => {
                check_on_cell(&self.path, &text, &task, cell_path, cell).map(|()| task)
            }
            None => Ok(task),
        });
        let task = checked.map_err(|error| match error {
            ConfigError::Invalid { message, .. } => invalid(message),
            other => invalid(other.to_string()),
        })?;
        self.table = table;
        self.task = task;
        Ok(())
    }
}

fn leaves(prefix: &str, value: &toml::Value, out: &mut Vec<(String, String)>) {
    match value {
        toml::Value::Table(table) => {
            for (key, inner) in table {
                leaves(&format!("{prefix}.{key}"), inner, out);
            }
        }
        leaf => out.push((prefix.to_owned(), leaf.to_string())),
    }
}

/// A TOML value; a bare word that is not one is taken as a string.
fn parse_value(text: &str) -> Result<toml::Value, String> {
    let parsed = |text: &str| {
        format!("v = {text}")
            .parse::<toml::Table>()
            .ok()
            .and_then(|mut t| t.remove("v"))
    };
    let bare_word = !text.is_empty() && text.chars().all(|c| c.is_alphanumeric() || c == '_');
    parsed(text)
        .or_else(|| bare_word.then(|| toml::Value::String(text.to_owned())))
        .ok_or_else(|| format!("`{text}` is not a value (a number, true/false, or a word)"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> TaskParams {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        TaskParams::load(&root.join("tasks/regrasp.toml")).unwrap()
    }

    #[test]
    fn lists_every_value_of_the_file_and_defaults() {
        let list = params().list();
        assert!(list.contains(&("tolerance.n_mm".into(), "1.0".into())));
        assert!(list.contains(&("tactile.estimator".into(), "\"centroids\"".into())));
        assert!(list.contains(&("regrasp.correction_gain.n".into(), "1.0".into())));
        assert!(!list.iter().any(|(name, _)| name.starts_with("task.")));
    }

    #[test]
    fn on_a_cell_a_speed_beyond_its_arm_is_refused_and_the_task_kept() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let cell_path = root.join("config/cell.sim.toml");
        let cell = crate::cell::load_cell(&cell_path).unwrap();
        let mut p =
            TaskParams::load_on_cell(&root.join("tasks/regrasp.toml"), &cell_path, &cell).unwrap();
        let error = p.set("approach.speed_mm_s", "250.5").unwrap_err();
        assert!(
            error
                .to_string()
                .starts_with("approach.speed_mm_s: expected a value in (0, 250] mm/s"),
            "{error}"
        );
        assert_eq!(p.task().approach.speed_mm_s, 100.0);
        p.set("approach.speed_mm_s", "250").unwrap();
        assert_eq!(p.task().approach.speed_mm_s, 250.0);
    }

    #[test]
    fn a_good_value_changes_the_task() {
        let mut p = params();
        p.set("tolerance.n_mm", "0.25").unwrap();
        p.set("tactile.estimator", "ridge").unwrap();
        p.set("regrasp.max_regrasps", "4").unwrap();
        p.set("regrasp.correction_gain.n", "1.2").unwrap();
        p.set("prior.max_search_moves", "9").unwrap();
        let task = p.task();
        assert_eq!(task.tolerance.n_mm, 0.25);
        assert_eq!(
            task.tactile.estimator,
            crate::perception::tactile::Estimator::Ridge
        );
        assert_eq!(task.regrasp.max_regrasps, 4);
        assert_eq!(task.regrasp.correction_gain.n, 1.2);
        assert_eq!(task.prior.as_ref().map(|p| p.max_search_moves), Some(9));
    }

    #[test]
    fn a_bad_value_is_refused_as_the_file_would_and_changes_nothing() {
        let mut p = params();
        let error = p.set("tolerance.n_mm", "-1").unwrap_err();
        assert_eq!(
            error,
            ParamError::Invalid {
                name: "tolerance.n_mm".into(),
                message: "expected a number > 0, found -1".into()
            }
        );
        assert!(
            p.set("tactile.estimator", "best")
                .unwrap_err()
                .to_string()
                .contains("unknown variant")
        );
        assert!(matches!(
            p.set("regrasp.max_regrasps", "1.5"),
            Err(ParamError::Invalid { .. })
        ));
        assert!(matches!(
            p.set("tolerance.n", "1"),
            Err(ParamError::Unknown { .. })
        ));
        assert!(matches!(
            p.set("tolerance", "1"),
            Err(ParamError::Unknown { .. })
        ));
        assert_eq!(p.task().tolerance.n_mm, 1.0);
        let error = p.set("prior.angle_sigma_rad", "2").unwrap_err();
        assert!(error.to_string().contains("[0, π/2]"), "{error}");
        assert!(matches!(
            p.set("prior.max_search_moves", "0"),
            Err(ParamError::Invalid { .. })
        ));
    }
}
