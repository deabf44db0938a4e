//! The device: a table of objects behind handles, and every ANARI call on
//! them in plain Rust, one file per topic (objects here; arrays,
//! parameters and commits, frames beside). Misuse is reported as a
//! `Status` and answered with a neutral value; nothing here panics on bad
//! input.

mod arrays;
mod frames;
mod params;

use crate::cluster::Ranks;
use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use super::geometry::GeometryModel;
use super::info;
use super::object::{ObjectCell, ObjectRef, State};
use super::object::{Params, Value};
use super::snapshot::Epoch;
use super::surface::SurfaceModel;
use super::types::{kind_name, object_kind, DataType, Reporter, Severity, Status, StatusCode};
use super::volume::VolumeModel;
use super::world::WorldModel;
use crate::engine::{About, Engine, FrameSlot, Note};
use crate::render::{Backend, StreamWait};
use crate::scene::SpatialField;

pub use frames::{Mapped, OnDone};

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
pub enum Subject {
    Device,
    Object(u64),
}

/// A property value for `anariGetProperty`.
#[derive(Clone, Debug, PartialEq)]
pub enum Property {
    Int32(i32),
    UInt64(u64),
    Float32(f32),
    /// FLOAT32_BOX3: lower corner, then upper corner.
    Box3([f32; 6]),
    Text(&'static std::ffi::CStr),
    /// The device's extension names (the C layer owns the C strings).
    Extensions,
    /// The implemented subtypes of an object kind (likewise).
    Subtypes(DataType),
}

/// `version.name`.
const VERSION_NAME: &std::ffi::CStr = match std::ffi::CStr::from_bytes_with_nul(
    concat!("caveray ", env!("CARGO_PKG_VERSION"), "\0").as_bytes(),
) {
    Ok(name) => name,
    Err(_) => c"caveray",
};

fn version_part(part: &str) -> i32 {
    part.parse().unwrap_or(0)
}

pub struct Device {
    /// Handles are `serial << 32 | n`, so a handle from another device is
    /// recognised without dereferencing anything.
    serial: u64,
    next: u64,
    objects: HashMap<u64, (ObjectRef, u32)>,
    pending: Params,
    committed: Params,
    /// Unknown device parameter names already warned about.
    warned: std::collections::BTreeSet<String>,
    /// Arrays handed out by `anariMapParameterArray*D`, by object and name.
    mapped_params: HashMap<(u64, String), (DataType, ObjectRef)>,
    backend: Backend,
    /// `caveray.memoryBudget`: bytes of volume textures the GPU may hold.
    gpu_budget: Option<u64>,
    /// `caveray.streamWait`: how long a frame waits for bricks.
    stream_wait: StreamWait,
    /// `pairStereoFrames`: frames that show the two eyes of one wall are
    /// found and rendered together.
    pairing: bool,
    /// `caveray.mpi`: the MPI job whose ranks composite every frame.
    ranks: Option<Arc<Ranks>>,
    statuses: Vec<Status>,
    /// Completion callbacks a call made due (a render refused at once),
    /// to be called by the caller once the device is unlocked.
    due: Vec<OnDone>,
    /// Counts commits, array changes and releases: a frame's snapshot
    /// stands while it is the same.
    epoch: Epoch,
    /// The render thread, deadline presenters and their warps.
    engine: Engine,
}

impl Device {
    /// `report` receives messages from the render thread; messages from
    /// calls are queued and taken with [`Device::take_statuses`].
    pub fn new(report: Reporter) -> Self {
        let backend = std::env::var("CAVERAY_BACKEND")
            .ok()
            .and_then(|b| b.parse().ok())
            .unwrap_or_default();
        Self {
            serial: NEXT_DEVICE.fetch_add(1, Ordering::Relaxed),
            next: 1,
            objects: HashMap::new(),
            pending: Params::default(),
            committed: Params::default(),
            warned: Default::default(),
            mapped_params: HashMap::new(),
            backend,
            gpu_budget: None,
            stream_wait: StreamWait::Complete,
            pairing: true,
            ranks: None,
            statuses: Vec::new(),
            due: Vec::new(),
            epoch: 0,
            engine: Engine::new(Arc::new(move |n: Note| {
                let (source, source_kind) = match n.about {
                    About::Device => (0, DataType::DEVICE),
                    About::Frame(handle) => (handle, DataType::FRAME),
                };
                report(Status {
                    severity: n.severity,
                    code: n.code,
                    source,
                    source_kind,
                    message: n.message,
                })
            })),
        }
    }

    /// Something a snapshot may have read changed.
    pub(super) fn changed(&mut self) {
        self.epoch += 1;
    }

    pub fn take_statuses(&mut self) -> Vec<Status> {
        std::mem::take(&mut self.statuses)
    }

    /// The completion callbacks the last calls made due.
    pub fn take_due(&mut self) -> Vec<OnDone> {
        std::mem::take(&mut self.due)
    }

    pub fn backend(&self) -> Backend {
        self.backend
    }

    pub fn gpu_budget(&self) -> Option<u64> {
        self.gpu_budget
    }

    pub fn stream_wait(&self) -> StreamWait {
        self.stream_wait
    }

    /// The MPI job frames are composited over (`caveray.mpi`), if any.
    pub fn ranks(&self) -> Option<&Arc<Ranks>> {
        self.ranks.as_ref()
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
    /// not implement give an inert object and a warning; any renderer
    /// subtype renders as the default renderer.
    pub fn new_object(&mut self, kind: DataType, subtype: &str) -> u64 {
        let table = info::for_new_object(kind, subtype);
        let implemented = table.is_some();
        let cell = self.insert(
            kind,
            subtype,
            implemented,
            info::initial_state(kind, implemented),
        );
        // An object never committed has its defaults (hosts use materials
        // and lights they never commit, and other devices draw them): its
        // state is a commit of no parameters, where that needs none.
        if let Some(t) = table.filter(|_| kind != DataType::FRAME) {
            if let (false, Some(commit)) = (t.params.iter().any(|p| p.required), t.commit) {
                let none = crate::device::object::Params::default();
                if let Ok(Some(state)) = commit(
                    &crate::device::table::Read::new(&none, t.params),
                    &mut |_| {},
                ) {
                    drop(cell.replace_state(state));
                }
            }
        }
        if let Some(t) = table.filter(|t| t.subtype != subtype && !t.subtype.is_empty()) {
            self.status(
                Severity::Info,
                StatusCode::NoError,
                Some(&cell),
                format!(
                    "{} '{subtype}' renders as caveray's '{}' {0}: {}",
                    kind_name(kind),
                    t.subtype,
                    t.description
                ),
            );
        }
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
        self.changed();
        let gone = match self.objects.get_mut(&handle) {
            Some(e) => {
                e.1 -= 1;
                e.1 == 0
            }
            None => false,
        };
        if gone {
            let entry = self.objects.remove(&handle);
            if let Some((cell, _)) = &entry {
                // Frames that name each other as stereo partners would
                // keep each other alive; a released frame renders no more.
                if cell.kind == DataType::FRAME {
                    forget_partner(cell);
                }
                // Still a parameter of something: keep what the host may
                // now free. Else no render reads it after those under way.
                if Arc::strong_count(cell) == 1 {
                    cell.with_array(|a| a.retire());
                } else {
                    let copied = cell.with_array(|a| a.privatize()).unwrap_or(Ok(false));
                    match copied {
                        Err(e) => self.error(
                            StatusCode::OutOfMemory,
                            Some(cell),
                            format!("anariRelease: {}: {e}", cell.describe()),
                        ),
                        Ok(true) => self.status(
                            Severity::PerformanceWarning,
                            StatusCode::NoError,
                            Some(cell),
                            format!(
                                "anariRelease: {}: the host's memory is still in use, so it was copied (release shared arrays after the objects that use them to avoid the copy)",
                                cell.describe()
                            ),
                        ),
                        Ok(false) => {}
                    }
                }
            }
            // Dropped outside the table borrow: the drop may run a host
            // deleter, which may call back into nothing of ours.
            drop(entry);
        }
    }

    /// The frames' partner references, so that frames naming each other
    /// do not outlive the device.
    fn forget_partners(&mut self) {
        for (cell, _) in self.objects.values() {
            if cell.kind == DataType::FRAME {
                forget_partner(cell);
            }
        }
    }

    /// `anariGetProperty`. `None`: no such property (not an error). With
    /// `wait`, a frame's render finishes first.
    pub fn property(&mut self, target: Subject, name: &str, wait: bool) -> Option<Property> {
        loop {
            match self.try_property(target, name, wait) {
                Ok(p) => return p,
                Err(slot) => drop(slot.wait()),
            }
        }
    }

    /// `property` without waiting: `Err(slot)` while a frame's render runs
    /// and `wait` asks for its end.
    pub fn try_property(
        &mut self,
        target: Subject,
        name: &str,
        wait: bool,
    ) -> Result<Option<Property>, Arc<FrameSlot>> {
        Ok(match target {
            Subject::Device => match name {
                "version" => Some(Property::Int32(1)),
                "version.major" => Some(Property::Int32(version_part(env!(
                    "CARGO_PKG_VERSION_MAJOR"
                )))),
                "version.minor" => Some(Property::Int32(version_part(env!(
                    "CARGO_PKG_VERSION_MINOR"
                )))),
                "version.patch" => Some(Property::Int32(version_part(env!(
                    "CARGO_PKG_VERSION_PATCH"
                )))),
                "version.name" => Some(Property::Text(VERSION_NAME)),
                "extension" => Some(Property::Extensions),
                "geometryMaxIndex" => Some(Property::UInt64(u64::from(u32::MAX))),
                _ => name
                    .strip_prefix("subtypes.")
                    .and_then(object_kind)
                    .map(Property::Subtypes),
            },
            Subject::Object(h) => {
                let Some(cell) = self.lookup(h, &format!("anariGetProperty('{name}')")) else {
                    return Ok(None);
                };
                let Some(slot) = cell.with_frame(|f| f.renders.slot.clone()) else {
                    return Ok(match name {
                        "bounds" => cell.usable::<WorldModel>().and_then(|w| world_bounds(&w)),
                        // A field's voxels, or a geometry's primitives and
                        // attributes, that the device holds (not the
                        // host's memory it reads in place).
                        "caveray.residentBytes" => {
                            let field = match cell.usable::<VolumeModel>() {
                                Some(volume) => volume.field.usable::<Arc<SpatialField>>(),
                                None => cell.usable::<Arc<SpatialField>>(),
                            };
                            let shape = || match cell.usable::<GeometryModel>()? {
                                GeometryModel::Shape(shape) => Some(shape.heap_bytes()),
                                GeometryModel::Iso(_) => None,
                            };
                            field
                                .map(|f| f.held_bytes())
                                .or_else(shape)
                                .map(Property::UInt64)
                        }
                        _ => None,
                    });
                };
                let s = slot.lock();
                if wait && s.busy && !s.finishes_here() {
                    drop(s);
                    return Err(slot);
                }
                match name {
                    "duration" => Some(Property::Float32(s.duration.as_secs_f32())),
                    // 0 while a render runs; after, the share of the
                    // bricks of paged volumes it selected that it
                    // rendered with (1 where nothing is paged).
                    "renderProgress" => Some(Property::Float32(if s.busy {
                        0.0
                    } else {
                        s.progress.unwrap_or(1.0)
                    })),
                    "numSamples" => Some(Property::Int32(s.samples as i32)),
                    // Volume samples the last image took, primary and
                    // shading: what benchmark hosts divide time by.
                    "caveray.volumeSamples" => match &s.result {
                        Some(Ok(frame)) => Some(Property::UInt64(frame.samples)),
                        _ => None,
                    },
                    // What a deadline frame showed (absent for a whole render).
                    "caveray.imageAge" => s.shown.map(|v| Property::Float32(v.age_ms)),
                    "caveray.warp" => s.shown.map(|v| Property::Text(warp_name(v.warp))),
                    // What the last render's volumes hold: voxels in host
                    // memory and the renderer's copies, and of that the
                    // GPU's textures.
                    "caveray.residentBytes" => s.resident.map(|r| Property::UInt64(r.host + r.gpu)),
                    "caveray.gpuBytes" => s.resident.map(|r| Property::UInt64(r.gpu)),
                    _ => None,
                }
            }
        })
    }
}

/// A warp's name as the C string `caveray.warp` answers with.
fn warp_name(mode: crate::render::warp::WarpMode) -> &'static std::ffi::CStr {
    use crate::render::warp::WarpMode;
    match mode {
        WarpMode::None => c"none",
        WarpMode::Quad => c"quad",
        WarpMode::Grid => c"grid",
        WarpMode::Layers => c"layers",
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

    /// The slot of a frame, to wait on without holding the device; `None`
    /// (and the error said) for what is not a frame, or a frame whose
    /// render only the calling thread can finish: a completion callback
    /// waiting on a render queued behind its own would wait forever.
    pub fn frame_slot(&mut self, handle: u64, call: &str) -> Option<Arc<FrameSlot>> {
        let cell = self.lookup(handle, call)?;
        let Some(slot) = cell.with_frame(|f| f.renders.slot.clone()) else {
            self.error(
                StatusCode::InvalidArgument,
                Some(&cell),
                format!("{call}: {} is not a frame", cell.describe()),
            );
            return None;
        };
        if slot.finishes_here() {
            self.still_rendering(&cell, call);
            return None;
        }
        Some(slot)
    }

    /// A committed parameter of an object (the C layer reads the frame's
    /// completion callback here).
    pub fn committed(&self, handle: u64, name: &str) -> Option<Value> {
        let cell = self.objects.get(&handle)?.0.clone();
        let g = cell.lock();
        g.committed.as_ref()?.get(name).cloned()
    }
}

/// The box around a world's volumes and surfaces, if any is ready.
fn world_bounds(world: &WorldModel) -> Option<Property> {
    let grid_of = |field: ObjectRef| Some(field.usable::<Arc<SpatialField>>()?.bounds());
    let box_of = |o: &ObjectRef| -> Option<(glam::Vec3, glam::Vec3)> {
        if let Some(volume) = o.usable::<VolumeModel>() {
            return grid_of(volume.field);
        }
        let geometry = o.usable::<SurfaceModel>()?.geometry;
        match geometry.usable::<GeometryModel>()? {
            GeometryModel::Iso(iso) => grid_of(iso.field),
            GeometryModel::Shape(shape) => Some(shape.bounds()).filter(|_| !shape.is_empty()),
        }
    };
    let placed = world.volumes.iter().chain(&world.surfaces);
    let mut boxes = placed.filter_map(|(v, placement)| {
        let grid = box_of(v)?;
        Some(match placement.transform {
            None => grid,
            Some(m) => crate::scene::transformed_box(m, grid),
        })
    });
    let (mut lo, mut hi) = boxes.next()?;
    for (l, h) in boxes {
        lo = lo.min(l);
        hi = hi.max(h);
    }
    Some(Property::Box3([lo.x, lo.y, lo.z, hi.x, hi.y, hi.z]))
}

impl Drop for Device {
    fn drop(&mut self) {
        self.forget_partners();
        self.engine.stop_presenters();
    }
}

/// Drops a frame's `stereoPartner`, pending and committed.
fn forget_partner(cell: &ObjectRef) {
    let mut o = cell.lock();
    o.pending.unset("stereoPartner");
    if let Some(c) = &mut o.committed {
        c.unset("stereoPartner");
    }
}
