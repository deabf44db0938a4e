//! Parameters: set (checked against the subtype's table), unset, and
//! committed, when the subtype's commit derives the object's state.

use super::{Device, Input, Subject};
use crate::device::object::{ObjectRef, Params, Value};
use crate::device::table::{ParamInfo, Read};
use crate::device::types::{DataType, Severity, StatusCode};
use crate::device::{device_object, info};
use crate::render::StreamWait;

impl Device {
    /// `anariSetParameter`: checked against the subtype's table. Unknown
    /// names are ignored with a warning; wrong types are errors.
    pub fn set_param(&mut self, target: Subject, name: &str, input: Input) {
        let (table, cell) = match target {
            Subject::Device => (Some(&device_object::INFO), None),
            Subject::Object(h) => match self.lookup(h, &format!("anariSetParameter('{name}')")) {
                Some(c) => (info::for_new_object(c.kind, &c.subtype), Some(c)),
                None => return,
            },
        };
        let owner = cell
            .as_ref()
            .map_or_else(|| "device".to_owned(), |c| c.describe());
        if cell.as_ref().is_some_and(|c| {
            !c.implemented
                || matches!(
                    c.kind,
                    DataType::ARRAY1D | DataType::ARRAY2D | DataType::ARRAY3D
                )
        }) {
            // Inert objects were warned about when created; arrays have no
            // parameters caveray reads.
            return;
        }
        let Some(param) = table.and_then(|t| t.params.iter().find(|p| p.name == name)) else {
            if info::IGNORED_PARAMS.contains(&name) {
                return;
            }
            let first = match &cell {
                Some(c) => c.lock().warned.insert(name.to_owned()),
                None => self.warned.insert(name.to_owned()),
            };
            if first {
                self.warn(
                    cell.as_ref(),
                    format!("anariSetParameter: {owner} has no parameter '{name}' that caveray reads; ignored (said once per object and name)"),
                );
            }
            return;
        };
        let declared = match &input {
            Input::Bytes(t, _) | Input::Pointer(t, _) | Input::Object(t, _) => *t,
            Input::String(_) => DataType::STRING,
        };
        let expected = param
            .types
            .iter()
            .map(|t| t.name())
            .collect::<Vec<_>>()
            .join(" or ");
        let value = match input {
            Input::Object(declared, h) => {
                let Some(object) = self.lookup(h, &format!("anariSetParameter: {owner} '{name}'"))
                else {
                    return;
                };
                let fits = param.types.iter().any(|&t| {
                    t.accepts_object(object.kind) && declared.accepts_object(object.kind)
                });
                if !fits {
                    self.error(
                        StatusCode::InvalidArgument,
                        cell.as_ref(),
                        format!(
                            "anariSetParameter: {owner} parameter '{name}' expects {expected}, got {} declared as {declared}",
                            object.describe()
                        ),
                    );
                    return;
                }
                Value::Object {
                    ty: object.kind,
                    object,
                }
            }
            _ if !param.types.contains(&declared) => {
                self.error(
                    StatusCode::InvalidArgument,
                    cell.as_ref(),
                    format!("anariSetParameter: {owner} parameter '{name}' expects {expected}, got {declared}"),
                );
                return;
            }
            Input::Bytes(ty, bytes) => Value::Bytes { ty, bytes },
            Input::String(s) => Value::String(s),
            Input::Pointer(ty, addr) => Value::Pointer { ty, addr },
        };
        match cell {
            None => self.pending.set(name, value),
            Some(c) => c.lock().pending.set(name, value),
        }
    }

    pub fn unset_param(&mut self, target: Subject, name: &str) {
        match target {
            Subject::Device => {
                self.pending.unset(name);
            }
            Subject::Object(h) => {
                if let Some(c) = self.lookup(h, "anariUnsetParameter") {
                    // Dropped outside the lock: it may be the last reference
                    // to an array whose host deleter then runs.
                    let removed = c.lock().pending.unset(name);
                    drop(removed);
                }
            }
        }
    }

    pub fn unset_all_params(&mut self, target: Subject) {
        match target {
            Subject::Device => self.pending.clear(),
            Subject::Object(h) => {
                if let Some(c) = self.lookup(h, "anariUnsetAllParameters") {
                    let old = std::mem::take(&mut c.lock().pending);
                    drop(old);
                }
            }
        }
    }

    /// A committed device parameter (the C layer reads its callbacks here).
    pub fn device_param(&self, name: &str) -> Option<&Value> {
        self.committed.get(name)
    }

    /// `anariCommitParameters`: the parameters set so far take effect and
    /// the subtype's commit rebuilds the object's state; problems are
    /// reported now.
    pub fn commit(&mut self, target: Subject) {
        self.changed();
        let cell = match target {
            Subject::Device => return self.commit_device(),
            Subject::Object(h) => match self.lookup(h, "anariCommitParameters") {
                Some(c) => c,
                None => return,
            },
        };
        let params = {
            let mut g = cell.lock();
            let p = g.pending.clone();
            g.committed = Some(p.clone());
            p
        };
        if !cell.implemented {
            return;
        }
        let Some(subtype) = info::for_new_object(cell.kind, &cell.subtype) else {
            return;
        };
        // Frames are committed before hosts know all they need; what is
        // missing is reported when they render.
        let missing = subtype
            .params
            .iter()
            .find(|p| p.required && params.get(p.name).is_none() && cell.kind != DataType::FRAME);
        let mut warnings = Vec::new();
        let read = Read::new(&params, subtype.params);
        let derived = match (missing, subtype.commit) {
            (Some(p), _) => Err(format!(
                "required parameter '{}' ({}) is not set",
                p.name, p.types[0]
            )),
            (None, Some(commit)) => commit(&read, &mut |w| warnings.push(w)),
            (None, None) => Ok(None),
        };
        let costs = read.take_costs();
        drop(read);
        let unset = self.drop_never_taken(&cell, subtype.params, &params);
        drop(params);
        for w in warnings {
            self.warn(
                Some(&cell),
                format!("anariCommitParameters: {}: {w}", cell.describe()),
            );
        }
        for c in costs {
            self.status(
                Severity::PerformanceWarning,
                StatusCode::NoError,
                Some(&cell),
                format!("anariCommitParameters: {}: {c}", cell.describe()),
            );
        }
        if derived.is_ok() && !unset.is_empty() {
            self.warn(
                Some(&cell),
                format!(
                    "anariCommitParameters: {}: {unset} (an array of what it never takes)",
                    cell.describe()
                ),
            );
        }
        let new_state = match derived {
            Ok(None) => return,
            Ok(Some(s)) => s,
            Err(e) => {
                let unset = if unset.is_empty() {
                    unset
                } else {
                    format!("; {unset}")
                };
                self.error(
                    StatusCode::InvalidArgument,
                    Some(&cell),
                    format!("anariCommitParameters: {}: {e}{unset}", cell.describe()),
                );
                match cell.invalid_state(e) {
                    Some(s) => s,
                    None => return,
                }
            }
        };
        let old = cell.replace_state(new_state);
        drop(old);
    }

    /// Unsets, pending and committed, the parameters whose values the
    /// table says they never take (`ParamInfo::never_takes`): what such a
    /// value holds stays alive no longer than the host's handles to it.
    /// Returns "'volume' is unset" (or "'a', 'b' are unset"), or "" when
    /// nothing was.
    fn drop_never_taken(
        &mut self,
        cell: &ObjectRef,
        table: &'static [ParamInfo],
        params: &Params,
    ) -> String {
        let names: Vec<&str> = table
            .iter()
            .filter(|p| params.get(p.name).is_some_and(|v| p.never_takes(v)))
            .map(|p| p.name)
            .collect();
        if names.is_empty() {
            return String::new();
        }
        let removed: Vec<_> = {
            let mut g = cell.lock();
            names
                .iter()
                .map(|n| {
                    let committed = g.committed.as_mut().and_then(|c| c.unset(n));
                    (g.pending.unset(n), committed)
                })
                .collect()
        };
        // Dropped outside the lock: the last reference to an array runs
        // its host deleter.
        drop(removed);
        let list = names
            .iter()
            .map(|n| format!("'{n}'"))
            .collect::<Vec<_>>()
            .join(", ");
        if names.len() == 1 {
            format!("{list} is unset")
        } else {
            format!("{list} are unset")
        }
    }

    fn commit_device(&mut self) {
        self.committed = self.pending.clone();
        self.pairing = self.committed.bool("pairStereoFrames").unwrap_or(true);
        self.gpu_budget = self
            .committed
            .get("caveray.memoryBudget")
            .and_then(|v| v.u64())
            .filter(|&b| b > 0);
        self.stream_wait = match self.committed.get("caveray.streamWait") {
            None => StreamWait::Complete,
            Some(v) => match v.f32s().as_deref() {
                Some(&[ms]) if ms.is_finite() && ms >= 0.0 => StreamWait::Budget {
                    wait: std::time::Duration::from_secs_f32(ms / 1000.0),
                    bricks: u32::MAX,
                },
                _ => {
                    self.error(
                        StatusCode::InvalidArgument,
                        None,
                        "anariCommitParameters: device parameter 'caveray.streamWait' must be one FLOAT32 of at least 0 milliseconds; frames wait for every brick".into(),
                    );
                    StreamWait::Complete
                }
            },
        };
        self.join_ranks();
        if let Some(b) = self.committed.string("backend") {
            match b.parse() {
                Ok(b) => self.backend = b,
                Err(_) => {
                    let b = b.to_owned();
                    self.error(
                        StatusCode::InvalidArgument,
                        None,
                        format!("anariCommitParameters: device parameter 'backend' is '{b}'; expected auto, gpu or cpu"),
                    );
                }
            }
        }
    }

    /// `caveray.mpi`: "world" makes every frame one of a data-parallel job
    /// over MPI_COMM_WORLD (joined once; the job stays for the device's
    /// life); unset, frames render alone.
    fn join_ranks(&mut self) {
        let wanted = self.committed.string("caveray.mpi").map(str::to_owned);
        let refuse = |d: &mut Self, why: String| {
            d.error(
                StatusCode::InvalidArgument,
                None,
                format!("anariCommitParameters: device parameter 'caveray.mpi': {why}; frames render alone"),
            );
            d.ranks = None;
        };
        match wanted.as_deref() {
            None => self.ranks = None,
            Some("world") if self.ranks.is_some() => {}
            Some("world") => {
                #[cfg(feature = "mpi")]
                match crate::cluster::Ranks::world() {
                    Ok(r) => self.ranks = Some(std::sync::Arc::new(r)),
                    Err(e) => refuse(self, format!("cannot join the MPI job: {e}")),
                }
                #[cfg(not(feature = "mpi"))]
                refuse(
                    self,
                    "this caveray was built without the mpi feature (cargo build --features mpi)"
                        .into(),
                );
            }
            Some(other) => refuse(self, format!("is '{other}'; the one value is \"world\"")),
        }
    }
}
