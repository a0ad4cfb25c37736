//! A curriculum file that builds on another, so that an experiment holds only what differs from the
//! curriculum it starts from (`configs/experiments/` builds on `configs/curriculum.toml`):
//!
//! ```toml
//! extends = "../curriculum.toml"   # relative to this file; that file may extend another in turn
//! stages_through = "efficient flight"  # the base's stages up to this one only (optional): stages
//!                                  # shipped later are left out, so the experiment keeps what it ran on
//! seed = 4                         # a key given here replaces the base's; tables merge key by key
//!
//! [[stages]]
//! modify = "cruise"                # the base's stage of that name, changed in place:
//! max_iterations = 400             # its keys replaced by these (tables merged key by key)
//!
//! [[stages]]
//! remove = "efficient flight"      # the base's stage of that name, left out (nothing else in the entry)
//!
//! [[stages]]
//! name = "flight modes"            # a new stage, appended at the end ...
//! after = "cruise"                 # ... or placed right after the stage of that name
//! from = "cruise"                  # ... starting as a copy of that stage, these keys over it
//! ```
//!
//! Everything else in a `[[stages]]` entry is a stage key, as in any curriculum file. Merging replaces
//! a value and never removes one: a stage that must lose a key of the one it would copy is written out
//! whole instead. The result is an ordinary curriculum table (a run saves it whole): nothing after
//! loading knows that a file extended another.

use std::path::{Path, PathBuf};

use toml::{Table, Value};

#[derive(Debug, thiserror::Error)]
pub enum OverlayError {
    #[error("curriculum config '{path}': cannot read it: {source}")]
    Read { path: String, source: std::io::Error },
    #[error("curriculum config '{path}': {message}")]
    Parse { path: String, message: String },
    #[error("curriculum config '{path}': extends '{base}', which cannot be read ({source})")]
    MissingBase { path: String, base: String, source: std::io::Error },
    #[error("curriculum config '{path}': extends '{base}', which extends it again ({chain})")]
    Circle { path: String, base: String, chain: String },
    #[error(
        "curriculum config '{path}': {place}{key} = '{stage}' names no stage of '{base}' (its stages: {known})",
        place = entry_place(*.entry)
    )]
    UnknownStage { path: String, entry: usize, key: &'static str, stage: String, base: String, known: String },
    #[error(
        "curriculum config '{path}': [[stages]] entry {entry}: a new stage named '{stage}', but '{base}' has one of that name; modify = '{stage}' changes it"
    )]
    StageExists { path: String, entry: usize, stage: String, base: String },
    #[error("curriculum config '{path}': [[stages]] entry {entry}: {message}")]
    BadEntry { path: String, entry: usize, message: String },
}

/// Where in a file an error's key is: its `[[stages]]` entry (counted from 1), or nothing for 0 (a
/// top-level key).
fn entry_place(entry: usize) -> String {
    if entry == 0 { String::new() } else { format!("[[stages]] entry {entry}: ") }
}

/// The key that names the file a curriculum builds on.
pub const EXTENDS: &str = "extends";
/// The key that keeps the base's stages up to and including the one it names, before the entries.
pub const STAGES_THROUGH: &str = "stages_through";

/// Whether a parsed curriculum file builds on another.
pub fn extends_another(file: &Table) -> bool {
    file.contains_key(EXTENDS)
}

/// `file` (parsed from `path`) laid over the file it extends, that one over the one it extends, and so
/// on: one curriculum table without `extends`.
pub fn resolve(path: &Path, file: Table) -> Result<Table, OverlayError> {
    resolve_chain(path, file, &mut Vec::new())
}

fn resolve_chain(path: &Path, mut file: Table, seen: &mut Vec<PathBuf>) -> Result<Table, OverlayError> {
    let shown = path.display().to_string();
    seen.push(path.canonicalize().unwrap_or_else(|_| path.to_owned()));
    let Some(extends) = file.remove(EXTENDS) else { return Ok(file) };
    let Value::String(base_name) = extends else {
        return Err(OverlayError::Parse {
            path: shown,
            message: format!("{EXTENDS} must be a file name, got {extends}"),
        });
    };
    let base_path = path.parent().unwrap_or(Path::new("")).join(&base_name);
    if seen.contains(&base_path.canonicalize().unwrap_or_else(|_| base_path.clone())) {
        let chain = seen.iter().chain([&base_path]).map(|p| p.display().to_string()).collect::<Vec<_>>();
        return Err(OverlayError::Circle { path: shown, base: base_name, chain: chain.join(" -> ") });
    }
    let text = std::fs::read_to_string(&base_path).map_err(|source| OverlayError::MissingBase {
        path: shown.clone(),
        base: base_name.clone(),
        source,
    })?;
    let base_file: Table = toml::from_str(&text).map_err(|e: toml::de::Error| OverlayError::Parse {
        path: base_path.display().to_string(),
        message: e.to_string(),
    })?;
    let mut base = resolve_chain(&base_path, base_file, seen)?;
    let through = match file.remove(STAGES_THROUGH) {
        None => None,
        Some(Value::String(stage)) => Some(stage),
        Some(other) => {
            let message = format!("{STAGES_THROUGH} must be a stage name, got {other}");
            return Err(OverlayError::Parse { path: shown, message });
        }
    };
    let entries = stage_list(file.remove("stages"), &shown)?;
    merge(&mut base, file);
    let base_shown = base_path.display().to_string();
    let mut stages: Vec<Table> = stage_list(base.remove("stages"), &base_shown)?
        .into_iter()
        .map(|stage| match stage {
            Value::Table(stage) => Ok(stage),
            other => Err(not_stages(&base_shown, &other)),
        })
        .collect::<Result<_, _>>()?;
    let names = Names { path: &shown, base: &base_name };
    if let Some(stage) = through {
        let at = find_stage(&stages, STAGES_THROUGH, &stage, 0, &names)?;
        stages.truncate(at + 1);
    }
    for (index, entry) in entries.into_iter().enumerate() {
        edit_stages(&mut stages, entry, index + 1, &names)?;
    }
    base.insert("stages".into(), Value::Array(stages.into_iter().map(Value::Table).collect()));
    Ok(base)
}

/// A file's `stages`: a list (of tables, which the entries' own checks see to), or none.
fn stage_list(stages: Option<Value>, path: &str) -> Result<Vec<Value>, OverlayError> {
    match stages {
        None => Ok(Vec::new()),
        Some(Value::Array(list)) => Ok(list),
        Some(other) => Err(not_stages(path, &other)),
    }
}

fn not_stages(path: &str, value: &Value) -> OverlayError {
    let message = format!("stages must be a list of [[stages]] tables, got {value}");
    OverlayError::Parse { path: path.to_owned(), message }
}

/// `over`'s keys into `base`: a table into a table key by key, any other value in place of the base's.
fn merge(base: &mut Table, over: Table) {
    for (key, value) in over {
        match (base.get_mut(&key), value) {
            (Some(Value::Table(inner)), Value::Table(value)) => merge(inner, value),
            (_, value) => {
                base.insert(key, value);
            }
        }
    }
}

/// The files an error names: the extending one and its base as `extends` wrote it.
struct Names<'a> {
    path: &'a str,
    base: &'a str,
}

/// Where the stage named `stage` is among `stages`, or the error naming `key` (with the `[[stages]]`
/// entry `number` it is in, or none for 0: a top-level key) and listing the stages there are.
fn find_stage(
    stages: &[Table],
    key: &'static str,
    stage: &str,
    number: usize,
    names: &Names,
) -> Result<usize, OverlayError> {
    stages.iter().position(|s| s.get("name").and_then(Value::as_str) == Some(stage)).ok_or_else(|| {
        let known: Vec<String> =
            stages.iter().filter_map(|s| s.get("name").and_then(Value::as_str)).map(|n| format!("'{n}'")).collect();
        OverlayError::UnknownStage {
            path: names.path.to_owned(),
            entry: number,
            key,
            stage: stage.to_owned(),
            base: names.base.to_owned(),
            known: known.join(", "),
        }
    })
}

/// One `[[stages]]` entry of an extending file applied to the stages so far.
fn edit_stages(stages: &mut Vec<Table>, entry: Value, number: usize, names: &Names) -> Result<(), OverlayError> {
    let bad = |message: String| OverlayError::BadEntry { path: names.path.to_owned(), entry: number, message };
    let Value::Table(mut entry) = entry else { return Err(bad("must be a table".into())) };
    let mut take = |key: &str| match entry.remove(key) {
        None => Ok(None),
        Some(Value::String(name)) => Ok(Some(name)),
        Some(other) => Err(bad(format!("{key} must be a stage name, got {other}"))),
    };
    let (modify, from, after, remove) = (take("modify")?, take("from")?, take("after")?, take("remove")?);
    let find = |key: &'static str, stage: &str| find_stage(stages, key, stage, number, names);
    if let Some(stage) = remove {
        if modify.is_some() || from.is_some() || after.is_some() || !entry.is_empty() {
            return Err(bad(format!("remove = '{stage}' leaves a stage out and takes no other key")));
        }
        let at = find("remove", &stage)?;
        stages.remove(at);
        return Ok(());
    }
    if let Some(stage) = modify {
        if from.is_some() || after.is_some() {
            return Err(bad(format!("modify = '{stage}' changes a stage in place; from and after are for new stages")));
        }
        let at = find("modify", &stage)?;
        merge(&mut stages[at], entry);
        return Ok(());
    }
    let Some(name) = entry.get("name").and_then(Value::as_str).map(str::to_owned) else {
        return Err(bad(format!("needs modify = \"STAGE\" (to change a stage of '{}') or name = \"NEW\"", names.base)));
    };
    if find("name", &name).is_ok() {
        let (path, base) = (names.path.to_owned(), names.base.to_owned());
        return Err(OverlayError::StageExists { path, entry: number, stage: name, base });
    }
    let mut stage = match from {
        Some(from) => stages[find("from", &from)?].clone(),
        None => Table::new(),
    };
    merge(&mut stage, entry);
    let at = match after {
        Some(after) => find("after", &after)? + 1,
        None => stages.len(),
    };
    stages.insert(at, stage);
    Ok(())
}
