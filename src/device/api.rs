//! The device: a table of objects behind handles, and every ANARI
//! operation on them in plain Rust. Misuse is reported as a `Status` and
//! answered with a neutral value; nothing here panics on bad input.

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use super::array::{byte_len, Array, HostMemory};
use super::commit;
use super::frame::FrameSlot;
use super::info;
use super::object::{Derived, ObjectCell, ObjectRef, State};
use super::types::{kind_name, DataType, Severity, Status, StatusCode};
use super::value::{Params, Value};
use super::worker::{BackendChoice, Reporter, Worker};
use super::CameraModel;

static NEXT_DEVICE: AtomicU64 = AtomicU64::new(1);

/// A parameter value as the host passed it, before it is checked.
pub enum Input {
    Bytes(DataType, Vec<u8>),
    String(String),
    Pointer(DataType, usize),
    /// A handle, with the type the host declared for it.
    Object(DataType, u64),
}

/// What a parameter or property call is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    Device,
    Object(u64),
}

/// A property value for `anariGetProperty`.
#[derive(Clone, Debug, PartialEq)]
pub enum Property {
    Int32(i32),
    UInt64(u64),
    Float32(f32),
    /// The device's extension names (the C layer owns the C strings).
    Extensions,
}

pub struct Device {
    /// Handles are `serial << 32 | n`, so a handle from another device is
    /// recognised without dereferencing anything.
    serial: u64,
    next: u64,
    objects: HashMap<u64, (ObjectRef, u32)>,
    pending: Params,
    committed: Params,
    /// Arrays handed out by `anariMapParameterArray*D`, by object and name.
    mapped_params: HashMap<(u64, String), (DataType, ObjectRef)>,
    backend: BackendChoice,
    statuses: Vec<Status>,
    pub(super) worker: Worker,
}

impl Device {
    /// `report` receives messages from the render thread; messages from
    /// calls are queued and taken with [`Device::take_statuses`].
    pub fn new(report: Reporter) -> Self {
        let backend = std::env::var("CAVERAY_BACKEND")
            .ok()
            .and_then(|b| BackendChoice::parse(&b))
            .unwrap_or(BackendChoice::Auto);
        Self {
            serial: NEXT_DEVICE.fetch_add(1, Ordering::Relaxed),
            next: 1,
            objects: HashMap::new(),
            pending: Params::default(),
            committed: Params::default(),
            mapped_params: HashMap::new(),
            backend,
            statuses: Vec::new(),
            worker: Worker::new(report),
        }
    }

    pub fn take_statuses(&mut self) -> Vec<Status> {
        std::mem::take(&mut self.statuses)
    }

    pub fn backend(&self) -> BackendChoice {
        self.backend
    }

    pub(super) fn status(
        &mut self,
        severity: Severity,
        code: StatusCode,
        source: Option<&ObjectRef>,
        message: String,
    ) {
        self.statuses.push(Status {
            severity,
            code,
            source: source.map_or(0, |o| o.handle),
            source_kind: source.map_or(DataType::DEVICE, |o| o.kind),
            message,
        });
    }

    pub(super) fn error(&mut self, code: StatusCode, source: Option<&ObjectRef>, message: String) {
        self.status(Severity::Error, code, source, message);
    }

    pub(super) fn warn(&mut self, source: Option<&ObjectRef>, message: String) {
        self.status(Severity::Warning, StatusCode::NoError, source, message);
    }

    /// The live object behind `handle`, or an error naming what is wrong
    /// with it (`what` says which argument it was, e.g. "anariCommitParameters").
    pub fn lookup(&mut self, handle: u64, what: &str) -> Option<ObjectRef> {
        if let Some((o, _)) = self.objects.get(&handle) {
            return Some(o.clone());
        }
        let message = if handle == 0 {
            format!("{what}: the object handle is NULL")
        } else if handle >> 32 == self.serial {
            format!("{what}: handle {handle:#x} was released (or never created)")
        } else if handle >> 32 != 0 && handle >> 32 < NEXT_DEVICE.load(Ordering::Relaxed) {
            format!("{what}: handle {handle:#x} belongs to another device")
        } else {
            format!("{what}: {handle:#x} is not an ANARI handle")
        };
        self.error(StatusCode::InvalidArgument, None, message);
        None
    }

    fn insert(
        &mut self,
        kind: DataType,
        subtype: &str,
        implemented: bool,
        state: State,
    ) -> ObjectRef {
        let handle = self.serial << 32 | self.next;
        self.next += 1;
        let cell = ObjectRef::new(ObjectCell::new(handle, kind, subtype, implemented, state));
        self.objects.insert(handle, (cell.clone(), 1));
        cell
    }

    /// `anariNew<Kind>` / `anariNewObject`. Kinds and subtypes caveray does
    /// not implement give an inert object and a warning.
    pub fn new_object(&mut self, kind: DataType, subtype: &str) -> u64 {
        let implemented = info::subtype(kind, subtype).is_some();
        let cell = self.insert(
            kind,
            subtype,
            implemented,
            State::for_kind(kind, implemented),
        );
        if !implemented {
            let known = info::subtypes(kind);
            let hint = if known.is_empty() {
                String::new()
            } else {
                format!(" (implemented: {})", known.join(", "))
            };
            self.warn(
                Some(&cell),
                format!(
                    "caveray does not implement {} '{subtype}'{hint}; the object is created but renders nothing",
                    kind_name(kind)
                ),
            );
        }
        cell.handle
    }

    /// `anariNewArray{1,2,3}D`. `memory` is the host's (shared array) or
    /// `None` (device-owned, zeroed). On failure the memory is handed back
    /// with `forget` so the host's deleter is not called for an array that
    /// never existed.
    pub fn new_array(
        &mut self,
        kind: DataType,
        element_code: i32,
        dims: [u64; 3],
        memory: Option<Box<dyn HostMemory>>,
    ) -> Result<u64, Option<Box<dyn HostMemory>>> {
        let what = match kind {
            DataType::ARRAY1D => "anariNewArray1D",
            DataType::ARRAY2D => "anariNewArray2D",
            _ => "anariNewArray3D",
        };
        let element = match DataType::from_code(element_code) {
            Some(t)
                if t.size() > 0
                    && !matches!(t, DataType::STRING_LIST | DataType::PARAMETER_LIST) =>
            {
                t
            }
            _ => {
                self.error(
                    StatusCode::InvalidArgument,
                    None,
                    format!(
                        "{what}: element type {element_code} is not a data type caveray can store"
                    ),
                );
                return Err(memory);
            }
        };
        if byte_len(element, dims).is_none() {
            self.error(
                StatusCode::OutOfMemory,
                None,
                format!("{what}: {dims:?} elements of {element} do not fit in memory"),
            );
            return Err(memory);
        }
        let array = match memory {
            Some(m) => Array::shared(element, dims, m),
            None => match Array::owned(element, dims) {
                Some(a) => a,
                None => {
                    self.error(
                        StatusCode::OutOfMemory,
                        None,
                        format!("{what}: cannot allocate {dims:?} elements of {element}"),
                    );
                    return Err(None);
                }
            },
        };
        let cell = self.insert(kind, "", true, State::Array(array));
        if element.is_object() {
            self.resolve_array_objects(&cell);
        }
        Ok(cell.handle)
    }

    /// Takes references to the objects an object array names.
    fn resolve_array_objects(&mut self, cell: &ObjectRef) {
        let (handles, element) = {
            let g = cell.lock();
            let State::Array(a) = &g.state else { return };
            (a.handles(), a.element())
        };
        let mut objects = Vec::with_capacity(handles.len());
        for (i, h) in handles.into_iter().enumerate() {
            if h == 0 {
                objects.push(None);
                continue;
            }
            let what = format!("{} element {i}", cell.describe());
            let o = self.lookup(h, &what);
            if let Some(o) = &o {
                if !element.accepts_object(o.kind) {
                    self.error(
                        StatusCode::InvalidArgument,
                        Some(cell),
                        format!("{what} is a {}, not {element}", kind_name(o.kind)),
                    );
                    objects.push(None);
                    continue;
                }
            }
            objects.push(o);
        }
        if let State::Array(a) = &mut cell.lock().state {
            a.objects = objects;
        }
    }

    /// Runs `f` on the array behind `handle`, or reports that it is none.
    fn with_array<R>(
        &mut self,
        handle: u64,
        call: &str,
        f: impl FnOnce(&mut Array) -> R,
    ) -> Option<(ObjectRef, R)> {
        let cell = self.lookup(handle, call)?;
        let result = match &mut cell.lock().state {
            State::Array(a) => Some(f(a)),
            _ => None,
        };
        match result {
            Some(r) => Some((cell, r)),
            None => {
                self.error(
                    StatusCode::InvalidArgument,
                    Some(&cell),
                    format!("{call}: {} is not an array", cell.describe()),
                );
                None
            }
        }
    }

    pub fn map_array(&mut self, handle: u64) -> *mut u8 {
        let mapped = self.with_array(handle, "anariMapArray", |a| {
            (!std::mem::replace(&mut a.mapped, true)).then(|| a.ptr())
        });
        match mapped {
            Some((_, Some(ptr))) => ptr,
            Some((cell, None)) => {
                self.error(
                    StatusCode::InvalidOperation,
                    Some(&cell),
                    format!(
                        "anariMapArray: {} is already mapped; unmap it first",
                        cell.describe()
                    ),
                );
                std::ptr::null_mut()
            }
            None => std::ptr::null_mut(),
        }
    }

    pub fn unmap_array(&mut self, handle: u64) {
        let Some((cell, (was_mapped, objects))) = self.with_array(handle, "anariUnmapArray", |a| {
            (
                std::mem::replace(&mut a.mapped, false),
                a.element().is_object(),
            )
        }) else {
            return;
        };
        if !was_mapped {
            self.error(
                StatusCode::InvalidOperation,
                Some(&cell),
                format!("anariUnmapArray: {} is not mapped", cell.describe()),
            );
        } else if objects {
            self.resolve_array_objects(&cell);
        }
    }

    pub fn retain(&mut self, handle: u64) {
        if self.lookup(handle, "anariRetain").is_some() {
            if let Some(e) = self.objects.get_mut(&handle) {
                e.1 += 1;
            }
        }
    }

    /// Drops the host's reference; the object lives on while parameters,
    /// arrays or a render in flight still use it.
    pub fn release(&mut self, handle: u64) {
        if self.lookup(handle, "anariRelease").is_none() {
            return;
        }
        let gone = match self.objects.get_mut(&handle) {
            Some(e) => {
                e.1 -= 1;
                e.1 == 0
            }
            None => false,
        };
        if gone {
            // Dropped outside the table borrow: the drop may run a host
            // deleter, which may call back into nothing of ours.
            let entry = self.objects.remove(&handle);
            drop(entry);
        }
    }

    /// `anariSetParameter`: checked against the subtype's table. Unknown
    /// names are ignored with a warning; wrong types are errors.
    pub fn set_param(&mut self, target: Target, name: &str, input: Input) {
        let (kind, subtype, cell) = match target {
            Target::Device => (DataType::DEVICE, "default".to_owned(), None),
            Target::Object(h) => match self.lookup(h, &format!("anariSetParameter('{name}')")) {
                Some(c) => (c.kind, c.subtype.clone(), Some(c)),
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
        let Some(param) = info::param(kind, &subtype, name) else {
            self.warn(
                cell.as_ref(),
                format!("anariSetParameter: {owner} has no parameter '{name}' that caveray reads; ignored"),
            );
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

    pub fn unset_param(&mut self, target: Target, name: &str) {
        match target {
            Target::Device => {
                self.pending.unset(name);
            }
            Target::Object(h) => {
                if let Some(c) = self.lookup(h, "anariUnsetParameter") {
                    // Dropped outside the lock: it may be the last reference
                    // to an array whose host deleter then runs.
                    let removed = c.lock().pending.unset(name);
                    drop(removed);
                }
            }
        }
    }

    pub fn unset_all_params(&mut self, target: Target) {
        match target {
            Target::Device => self.pending.clear(),
            Target::Object(h) => {
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
    /// the object's derived state is rebuilt; problems are reported now.
    pub fn commit(&mut self, target: Target) {
        let cell = match target {
            Target::Device => return self.commit_device(),
            Target::Object(h) => match self.lookup(h, "anariCommitParameters") {
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
        let mut warnings = Vec::new();
        let mut warn = |m: String| warnings.push(m);
        let missing = info::subtype(cell.kind, &cell.subtype)
            .into_iter()
            .flat_map(|s| s.params)
            .find(|p| p.required && params.get(p.name).is_none() && cell.kind != DataType::FRAME);
        let derived: Option<Result<State, String>> = match (missing, cell.kind) {
            (Some(p), _) => Some(Err(format!(
                "required parameter '{}' ({}) is not set",
                p.name, p.types[0]
            ))),
            (None, DataType::SPATIAL_FIELD) => Some(
                commit::structured_regular(&params, &mut warn)
                    .map(|v| State::Field(Derived::Ready(v))),
            ),
            (None, DataType::VOLUME) => Some(
                commit::transfer_function_1d(&params).map(|v| State::Volume(Derived::Ready(v))),
            ),
            (None, DataType::WORLD) => {
                Some(commit::world(&params).map(|v| State::World(Derived::Ready(v))))
            }
            (None, DataType::CAMERA) => Some(
                CameraModel::from_params(&cell.subtype, &params)
                    .map(|v| State::Camera(Derived::Ready(v))),
            ),
            (None, DataType::RENDERER) => {
                Some(commit::renderer(&params).map(|v| State::Renderer(Derived::Ready(v))))
            }
            (None, DataType::FRAME) => {
                self.check_frame(&cell, &params);
                None
            }
            _ => None,
        };
        for w in warnings {
            self.warn(
                Some(&cell),
                format!("anariCommitParameters: {}: {w}", cell.describe()),
            );
        }
        let Some(derived) = derived else { return };
        let new_state = match derived {
            Ok(s) => s,
            Err(e) => {
                self.error(
                    StatusCode::InvalidArgument,
                    Some(&cell),
                    format!("anariCommitParameters: {}: {e}", cell.describe()),
                );
                invalid_state(cell.kind, e)
            }
        };
        let old = std::mem::replace(&mut cell.lock().state, new_state);
        drop(old);
    }

    fn commit_device(&mut self) {
        self.committed = self.pending.clone();
        if let Some(b) = self.committed.string("backend") {
            match BackendChoice::parse(b) {
                Some(b) => self.backend = b,
                None => {
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

    /// Frame parameters are read at render time; commit only warns early.
    fn check_frame(&mut self, cell: &ObjectRef, p: &Params) {
        if let Some(code) = p.get("channel.color").and_then(|v| v.i32()) {
            let ty = DataType::from_code(code);
            if super::frames::color_format(ty).is_none() {
                self.error(
                    StatusCode::InvalidArgument,
                    Some(cell),
                    format!(
                        "anariCommitParameters: {}: channel.color {} is not UFIXED8_VEC4, UFIXED8_RGBA_SRGB or FLOAT32_VEC4",
                        cell.describe(),
                        ty.map_or_else(|| code.to_string(), |t| t.name().to_owned())
                    ),
                );
            }
        }
    }

    /// `anariGetProperty`. `None`: no such property (not an error).
    pub fn property(&mut self, target: Target, name: &str, wait: bool) -> Option<Property> {
        match target {
            Target::Device => match name {
                "version" => Some(Property::Int32(1)),
                "extension" => Some(Property::Extensions),
                "geometryMaxIndex" => Some(Property::UInt64(u64::from(u32::MAX))),
                _ => None,
            },
            Target::Object(h) => {
                let cell = self.lookup(h, &format!("anariGetProperty('{name}')"))?;
                let slot = match (&cell.lock().state, name) {
                    (State::Frame(f), "duration") => f.slot.clone(),
                    _ => return None,
                };
                let s = if wait { slot.wait() } else { slot.lock() };
                Some(Property::Float32(s.duration.as_secs_f32()))
            }
        }
    }

    /// `anariMapParameterArray*D`: a device-owned array the host fills,
    /// set as parameter `name` when unmapped.
    /// `anariMapParameterArray*D`: a device-owned array of `kind` the host
    /// fills, set as parameter `name` when unmapped.
    pub fn map_param_array(
        &mut self,
        handle: u64,
        name: &str,
        kind: DataType,
        element_code: i32,
        dims: [u64; 3],
    ) -> (*mut u8, u64) {
        let Some(cell) = self.lookup(handle, &format!("anariMapParameterArray('{name}')")) else {
            return (std::ptr::null_mut(), 0);
        };
        let key = (handle, name.to_owned());
        if self.mapped_params.contains_key(&key) {
            self.error(
                StatusCode::InvalidOperation,
                Some(&cell),
                format!(
                    "anariMapParameterArray: '{name}' of {} is already mapped",
                    cell.describe()
                ),
            );
            return (std::ptr::null_mut(), 0);
        }
        let Ok(array) = self.new_array(kind, element_code, dims, None) else {
            return (std::ptr::null_mut(), 0);
        };
        let ptr = self.map_array(array);
        if let Some((array_cell, _)) = self.objects.get(&array) {
            self.mapped_params.insert(key, (kind, array_cell.clone()));
        }
        // The parameter map holds the array now, not the host.
        self.release(array);
        let element = DataType::from_code(element_code).map_or(0, |t| t.size() as u64);
        (ptr, element)
    }

    pub fn unmap_param_array(&mut self, handle: u64, name: &str) {
        let Some(cell) = self.lookup(handle, &format!("anariUnmapParameterArray('{name}')")) else {
            return;
        };
        let Some((kind, array)) = self.mapped_params.remove(&(handle, name.to_owned())) else {
            self.error(
                StatusCode::InvalidOperation,
                Some(&cell),
                format!(
                    "anariUnmapParameterArray: '{name}' of {} is not mapped",
                    cell.describe()
                ),
            );
            return;
        };
        // Back in the table for the unmap and the set, then the host-side
        // reference goes again.
        let h = array.handle;
        self.objects.insert(h, (array, 1));
        self.unmap_array(h);
        self.set_param(Target::Object(handle), name, Input::Object(kind, h));
        self.release(h);
    }
}

fn invalid_state(kind: DataType, why: String) -> State {
    match kind {
        DataType::SPATIAL_FIELD => State::Field(Derived::Invalid(why)),
        DataType::VOLUME => State::Volume(Derived::Invalid(why)),
        DataType::WORLD => State::World(Derived::Invalid(why)),
        DataType::CAMERA => State::Camera(Derived::Invalid(why)),
        DataType::RENDERER => State::Renderer(Derived::Invalid(why)),
        _ => State::Inert,
    }
}

impl Device {
    /// An error about a call's arguments, found before the device model
    /// was reached (e.g. a string that is not UTF-8).
    pub fn report_error(&mut self, code: StatusCode, message: String) {
        self.error(code, None, message);
    }

    /// The kind of a live object, without reporting anything.
    pub fn kind_of(&self, handle: u64) -> Option<DataType> {
        self.objects.get(&handle).map(|e| e.0.kind)
    }

    /// The slot of a frame, to wait on without holding the device.
    pub fn frame_slot(&mut self, handle: u64, call: &str) -> Option<Arc<FrameSlot>> {
        let cell = self.lookup(handle, call)?;
        let slot = match &cell.lock().state {
            State::Frame(f) => Some(f.slot.clone()),
            _ => None,
        };
        if slot.is_none() {
            self.error(
                StatusCode::InvalidArgument,
                Some(&cell),
                format!("{call}: {} is not a frame", cell.describe()),
            );
        }
        slot
    }

    /// A committed parameter of an object (the C layer reads the frame's
    /// completion callback here).
    pub fn committed(&self, handle: u64, name: &str) -> Option<Value> {
        let cell = self.objects.get(&handle)?.0.clone();
        let g = cell.lock();
        g.committed.as_ref()?.get(name).cloned()
    }
}
