//! What each fuzz target feeds its input to. Kept apart from libFuzzer so
//! that `tests/fuzz_corpus/main.rs` replays the committed corpus and every
//! input that once crashed through the same code on stable Rust.
//! Every function here must return, whatever its input: a panic, abort,
//! hang or out-of-memory is a bug in caveray.

use std::ffi::{c_void, CString};
use std::path::Path;
use std::sync::Mutex;

use anari_library_caveray::capi::entry_points::*;
use anari_library_caveray::capi::sys;
use anari_library_caveray::cave::{MultiViewDisplay, Rig};
use anari_library_caveray::data::{
    parse_dicom, parse_metaimage, parse_nifti, parse_nrrd, parse_paraview, parse_raw, parse_vtk,
    parse_vtk_mesh, sniff, Manifest, VoxelType,
};
use anari_library_caveray::device::info::SUBTYPES;
use anari_library_caveray::device::DataType;
use glam::{UVec3, Vec3};

/// A rig file: any text.
pub fn rig(data: &[u8]) {
    if let Ok(text) = std::str::from_utf8(data) {
        if let Ok(rig) = Rig::from_toml(text, "fuzz.toml") {
            // What the tool does next with a rig: views of every wall.
            let _ = rig.views(&rig.viewer.head);
        }
    }
}

/// A multi-view display file: any text.
pub fn display(data: &[u8]) {
    if let Ok(text) = std::str::from_utf8(data) {
        if let Ok(display) = MultiViewDisplay::from_toml(text, "fuzz.toml") {
            // What the tool does next with a display: every view's rays,
            // and the view and eye of subpixels across the panel.
            let _ = display.view_rays();
            let r = display.resolution;
            for (x, y) in [(0, 0), (r.x - 1, r.y - 1), (r.x / 2, r.y / 3)] {
                for c in 0..3 {
                    let _ = display.subpixel_eye(x, y, c);
                }
            }
        }
    }
}

/// A ParaView color map: any text.
pub fn paraview(data: &[u8]) {
    if let Ok(text) = std::str::from_utf8(data) {
        if let Ok(tf) = parse_paraview(text, "fuzz.json") {
            let _ = tf.table();
        }
    }
}

/// A manifest (the text before the first NUL) and a raw volume (the
/// bytes after it) read as the manifest's first entry describes it; the
/// volume's bytes are also sniffed for a header format, as the tool does
/// before reading a file as raw.
pub fn raw_manifest(data: &[u8]) {
    let split = data.iter().position(|&b| b == 0).unwrap_or(data.len());
    let (text, bytes) = (&data[..split], data.get(split + 1..).unwrap_or(&[]));
    let _ = sniff("fuzz.raw", bytes);
    let _ = sniff("fuzz", bytes);
    let Ok(text) = std::str::from_utf8(text) else {
        return;
    };
    let Ok(manifest) = Manifest::parse(text, Path::new("fuzz/volumes.toml")) else {
        return;
    };
    let Some(entry) = manifest.entries().first() else {
        return;
    };
    let _ = (manifest.find(&entry.name), manifest.file_of(entry));
    let Ok(dtype) = VoxelType::parse(&entry.dtype) else {
        return;
    };
    let dims = UVec3::from_array(entry.dims);
    if let Ok(v) = parse_raw(
        bytes,
        "fuzz.raw",
        dims,
        dtype,
        Vec3::from_array(entry.spacing),
    ) {
        let _ = v.value_range();
    }
}

/// A NIfTI file: any bytes, read as a `.nii` and, gunzipped, as a
/// `.nii.gz`.
pub fn nifti(data: &[u8]) {
    for name in ["fuzz.nii", "fuzz.nii.gz"] {
        if let Ok(n) = parse_nifti(data, name) {
            let _ = (n.volume.value_range(), n.transform());
        }
    }
}

/// A NRRD file with its voxels attached: any bytes.
pub fn nrrd(data: &[u8]) {
    if let Ok(n) = parse_nrrd(data, "fuzz.nrrd") {
        let _ = (n.volume.value_range(), n.transform());
    }
}

/// A MetaImage file with its voxels attached (`.mha`): any bytes.
pub fn metaimage(data: &[u8]) {
    if let Ok(m) = parse_metaimage(data, "fuzz.mha") {
        let _ = (m.volume.value_range(), m.transform());
    }
}

/// A VTK image data file, legacy or XML: any bytes.
pub fn vtk(data: &[u8]) {
    if let Ok(v) = parse_vtk(data, "fuzz.vti") {
        let _ = (v.volume.value_range(), v.transform());
    }
}

/// One DICOM file (a series of its own): any bytes.
pub fn dicom(data: &[u8]) {
    if let Ok(d) = parse_dicom(data, "fuzz.dcm") {
        let _ = (d.volume.value_range(), d.transform());
    }
}

/// The crates whose panics the DICOM reader catches: dicom-rs's pixel
/// decoding and the codecs under it.
const CODECS: [&str; 4] = [
    "/dicom-pixeldata-",
    "/dicom-transfer-syntax-registry-",
    "/jpeg-decoder-",
    "/jpeg2k-",
];

/// For the dicom target: dicom-rs's codecs panic on some broken frames,
/// which the reader catches and reports as the file's error, as a host
/// sees it. libFuzzer's hook aborts on any panic before it can be caught,
/// so it is kept for every panic but those raised inside the codecs; a
/// panic the reader does not catch still aborts in libfuzzer-sys.
pub fn codec_panics_are_errors() {
    let fuzzer_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let file = info.location().map_or("", |l| l.file());
        if !CODECS.iter().any(|c| file.contains(c)) {
            fuzzer_hook(info);
        }
    }));
}

/// Bytes read in order, zeros once they run out.
struct Input<'a>(&'a [u8]);

impl Input<'_> {
    fn byte(&mut self) -> u8 {
        let (b, rest) = self.0.split_first().map_or((0, &[][..]), |(b, r)| (*b, r));
        self.0 = rest;
        b
    }
    fn take(&mut self, n: usize) -> Vec<u8> {
        let n = n.min(self.0.len());
        let (head, rest) = self.0.split_at(n);
        self.0 = rest;
        head.to_vec()
    }
    fn pick<'t, T>(&mut self, items: &'t [T]) -> &'t T {
        &items[usize::from(self.byte()) % items.len()]
    }
    fn done(&self) -> bool {
        self.0.is_empty()
    }
}

unsafe extern "C" fn quiet(
    _: *const c_void,
    _: sys::ANARIDevice,
    _: sys::ANARIObject,
    _: sys::ANARIDataType,
    _: sys::ANARIStatusSeverity,
    _: sys::ANARIStatusCode,
    _: *const std::ffi::c_char,
) {
}

/// The library, loaded for one input as a host loads it.
fn library() -> sys::ANARILibrary {
    // SAFETY: a valid name and callback.
    unsafe { anariLoadLibrary(c"caveray".as_ptr(), Some(quiet), std::ptr::null()) }
}

/// Types a host may pass to anariSetParameter with `mem` pointing at
/// that many bytes (lists and callbacks, whose pointers caveray follows,
/// are left out: garbage there is the host's fault, not ours).
fn settable() -> Vec<DataType> {
    DataType::ALL
        .iter()
        .copied()
        .filter(|t| {
            !matches!(
                t,
                DataType::STRING_LIST
                    | DataType::DATA_TYPE_LIST
                    | DataType::PARAMETER_LIST
                    | DataType::STATUS_CALLBACK
                    | DataType::FRAME_COMPLETION_CALLBACK
                    | DataType::VOID_POINTER
            )
        })
        .collect()
}

/// What both host threads pick from: subtypes, parameter names and types.
struct Words {
    types: Vec<DataType>,
    names: Vec<&'static str>,
    subtypes: Vec<&'static str>,
}

impl Words {
    fn new() -> Self {
        let mut names: Vec<&str> = SUBTYPES
            .iter()
            .flat_map(|s| s.params.iter().map(|p| p.name))
            .filter(|n| *n != "size")
            .collect();
        names.extend(["", "name", "ünïcode", "channel.normal"]);
        let mut subtypes: Vec<&str> = SUBTYPES.iter().map(|s| s.subtype).collect();
        subtypes.extend(["", "pathtracer", "unknown"]);
        Self {
            types: settable(),
            names,
            subtypes,
        }
    }
}

/// The callbacks' script: what the frame completion and status callbacks
/// do, one byte per action, taken in the order they are called; and the
/// handles the host handed them (retained for them), which they may
/// release. Static, since a render thread may still be leaving a callback
/// when `capi` returns; each input starts it afresh.
struct Callbacks {
    script: Vec<u8>,
    at: usize,
    owned: Vec<usize>,
}

static CALLBACKS: Mutex<Callbacks> = Mutex::new(Callbacks {
    script: Vec::new(),
    at: 0,
    owned: Vec::new(),
});

fn callbacks() -> std::sync::MutexGuard<'static, Callbacks> {
    CALLBACKS.lock().unwrap_or_else(|e| e.into_inner())
}

/// The callbacks' next action byte, if the script has one left.
fn next_action() -> Option<u8> {
    let mut c = callbacks();
    let b = c.script.get(c.at).copied();
    c.at += usize::from(b.is_some());
    b
}

/// A handle the host handed the callbacks, taken (to release) or looked at.
fn owned(take: bool) -> Option<usize> {
    let mut c = callbacks();
    if take {
        c.owned.pop()
    } else {
        c.owned.last().copied()
    }
}

thread_local! {
    /// How deep this thread is in callbacks calling back into the API
    /// (which may report a status, which calls the status callback...).
    static DEPTH: std::cell::Cell<u8> = const { std::cell::Cell::new(0) };
}

/// Runs `f` unless this thread is already two callbacks deep.
fn reenter(f: impl FnOnce()) {
    let depth = DEPTH.with(|d| d.get());
    if depth >= 2 {
        return;
    }
    DEPTH.with(|d| d.set(depth + 1));
    f();
    DEPTH.with(|d| d.set(depth));
}

/// Every channel a frame can be asked for, mapped after a render.
const CHANNELS: [&std::ffi::CStr; 7] = [
    c"channel.color",
    c"channel.depth",
    c"channel.primitiveId",
    c"channel.objectId",
    c"channel.instanceId",
    c"channel.normal",
    c"channel.albedo",
];

const FRAME_PROPERTIES: [&std::ffi::CStr; 5] = [
    c"duration",
    c"numSamples",
    c"renderProgress",
    c"caveray.imageAge",
    c"caveray.volumeSamples",
];

/// `anariGetProperty` of a frame property, as a FLOAT32 (or anything
/// four bytes long), waiting or not.
unsafe fn frame_property(dev: sys::ANARIDevice, frame: sys::ANARIObject, b: u8, wait: bool) {
    let mut out = [0u8; 8];
    let name = FRAME_PROPERTIES[usize::from(b) % FRAME_PROPERTIES.len()];
    anariGetProperty(
        dev,
        frame,
        name.as_ptr(),
        DataType::FLOAT32 as i32,
        out.as_mut_ptr().cast(),
        4,
        u32::from(wait),
    );
}

/// The frame completion callback: each call takes one to three actions
/// from the script, calling back into the API from the render thread (or
/// a deadline frame's presenter).
unsafe extern "C" fn on_frame_done(
    _: *const c_void,
    dev: sys::ANARIDevice,
    frame: sys::ANARIFrame,
) {
    reenter(|| {
        let Some(first) = next_action() else { return };
        for _ in 0..=first % 3 {
            let Some(b) = next_action() else { return };
            match b % 11 {
                0 => {
                    let mut version = 0i32;
                    anariGetProperty(
                        dev,
                        dev,
                        c"version".as_ptr(),
                        DataType::INT32 as i32,
                        (&mut version as *mut i32).cast(),
                        4,
                        0,
                    );
                }
                1 => frame_property(dev, frame, b / 11, false),
                // Waiting on the very frame this callback finishes.
                2 => frame_property(dev, frame, b / 11, true),
                3 => {
                    anariFrameReady(dev, frame, 0);
                }
                4 => {
                    anariFrameReady(dev, frame, 1);
                }
                5 => anariRenderFrame(dev, frame),
                6 => anariDiscardFrame(dev, frame),
                7 => {
                    let (mut w, mut h, mut t) = (0u32, 0u32, 0i32);
                    let channel = c"channel.color".as_ptr();
                    if !anariMapFrame(dev, frame, channel, &mut w, &mut h, &mut t).is_null() {
                        anariUnmapFrame(dev, frame, channel);
                    }
                }
                // Another frame (or anything) the host handed the callbacks.
                8 => {
                    if let Some(other) = owned(false) {
                        let other = other as sys::ANARIFrame;
                        anariRenderFrame(dev, other);
                        anariFrameReady(dev, other, u32::from(b & 0x80 != 0));
                    }
                }
                // Releasing a handle the host handed over: a frame, the
                // device, anything.
                9 => {
                    if let Some(h) = owned(true) {
                        anariRelease(dev, h as sys::ANARIObject);
                    }
                }
                _ => {
                    anariCommitParameters(dev, frame);
                }
            }
        }
    })
}

/// The device's status callback: one action from the script per message.
unsafe extern "C" fn on_status(
    _: *const c_void,
    dev: sys::ANARIDevice,
    source: sys::ANARIObject,
    source_type: sys::ANARIDataType,
    _: sys::ANARIStatusSeverity,
    _: sys::ANARIStatusCode,
    _: *const std::ffi::c_char,
) {
    reenter(|| {
        let Some(b) = next_action() else { return };
        match b % 6 {
            0 => {
                let mut out = [0u8; 24];
                anariGetProperty(
                    dev,
                    source,
                    c"bounds".as_ptr(),
                    DataType::FLOAT32_BOX3 as i32,
                    out.as_mut_ptr().cast(),
                    24,
                    0,
                );
            }
            1 if source_type == DataType::FRAME as i32 => {
                anariFrameReady(dev, source, 0);
                frame_property(dev, source, b / 6, false);
            }
            2 => {
                if let Some(h) = owned(true) {
                    anariRelease(dev, h as sys::ANARIObject);
                }
            }
            _ => {}
        }
    })
}

/// One host thread: its script, the device, the handles it made and
/// those it may use but does not own (the other thread's).
struct Host<'a, 'w> {
    input: Input<'a>,
    dev: sys::ANARIDevice,
    words: &'w Words,
    objects: Vec<sys::ANARIObject>,
    shared: Vec<usize>,
}

impl Host<'_, '_> {
    /// A handle from the script: one of the thread's own or shared ones,
    /// NULL, garbage, or (with none yet) a small number.
    fn handle(&mut self) -> sys::ANARIObject {
        let n = self.objects.len() + self.shared.len();
        match self.input.byte() {
            255 => 0x1234 as sys::ANARIObject,
            254 => std::ptr::null_mut(),
            i if n == 0 => i as usize as sys::ANARIObject,
            i => {
                let i = usize::from(i) % n;
                match self.objects.get(i) {
                    Some(&o) => o,
                    None => self.shared[i - self.objects.len()] as sys::ANARIObject,
                }
            }
        }
    }

    unsafe fn create(&mut self) {
        let dev = self.dev;
        let sub = CString::new(*self.input.pick(&self.words.subtypes)).unwrap_or_default();
        let s = sub.as_ptr();
        let o = match self.input.byte() % 11 {
            0 => anariNewCamera(dev, s),
            1 => anariNewSpatialField(dev, s),
            2 => anariNewVolume(dev, s),
            3 => anariNewRenderer(dev, s),
            4 => anariNewLight(dev, s),
            5 => anariNewInstance(dev, s),
            6 => anariNewGroup(dev),
            7 => anariNewWorld(dev),
            8 => anariNewFrame(dev),
            9 => anariNewGeometry(dev, s),
            _ => anariNewObject(dev, c"extension".as_ptr(), s),
        };
        if !o.is_null() {
            self.objects.push(o);
        }
    }

    unsafe fn set(&mut self) {
        let dev = self.dev;
        let o = self.handle();
        let name = CString::new(*self.input.pick(&self.words.names)).unwrap_or_default();
        let ty = *self.input.pick(&self.words.types);
        if ty == DataType::STRING {
            let len = usize::from(self.input.byte() % 16);
            let text = CString::new(
                self.input
                    .take(len)
                    .into_iter()
                    .filter(|&b| b != 0)
                    .collect::<Vec<u8>>(),
            )
            .unwrap_or_default();
            anariSetParameter(dev, o, name.as_ptr(), ty as i32, text.as_ptr().cast());
        } else if ty.is_object() {
            let h = self.handle();
            anariSetParameter(
                dev,
                o,
                name.as_ptr(),
                ty as i32,
                (&h as *const sys::ANARIObject).cast(),
            );
        } else {
            let mut mem = self.input.take(ty.size());
            mem.resize(ty.size().max(1), 0);
            anariSetParameter(dev, o, name.as_ptr(), ty as i32, mem.as_ptr().cast());
        }
    }

    unsafe fn array(&mut self) {
        let dev = self.dev;
        let element = *self.input.pick(&self.words.types);
        let dims = [
            self.input.byte() % 17,
            self.input.byte() % 17,
            self.input.byte() % 17,
        ]
        .map(u64::from);
        let rank = usize::from(self.input.byte() % 3) + 1;
        let none = std::ptr::null();
        let ty = element as i32;
        let a = match rank {
            1 => anariNewArray1D(dev, none, None, none, ty, dims[0]),
            2 => anariNewArray2D(dev, none, None, none, ty, dims[0], dims[1]),
            _ => anariNewArray3D(dev, none, None, none, ty, dims[0], dims[1], dims[2]),
        };
        if !a.is_null() {
            let p = anariMapArray(dev, a);
            if !p.is_null() && !element.is_object() {
                let count: u64 = dims[..rank].iter().product();
                let bytes = count as usize * element.size();
                let fill = self.input.take(bytes);
                std::ptr::copy_nonoverlapping(fill.as_ptr(), p.cast::<u8>(), fill.len());
            }
            anariUnmapArray(dev, a);
            self.objects.push(a);
        }
    }

    unsafe fn render(&mut self) {
        let dev = self.dev;
        let f = self.handle();
        let size = [
            u32::from(self.input.byte() % 64) + 1,
            u32::from(self.input.byte() % 64) + 1,
        ];
        anariSetParameter(
            dev,
            f,
            c"size".as_ptr(),
            DataType::UINT32_VEC2 as i32,
            size.as_ptr().cast(),
        );
        anariCommitParameters(dev, f);
        anariRenderFrame(dev, f);
        if self.input.byte().is_multiple_of(4) {
            anariDiscardFrame(dev, f);
        }
        anariFrameReady(dev, f, sys::ANARIWaitMask::from(1u32));
        let (mut w, mut h, mut t) = (0u32, 0u32, 0i32);
        let channel = CHANNELS[usize::from(self.input.byte()) % CHANNELS.len()];
        let p = anariMapFrame(dev, f, channel.as_ptr(), &mut w, &mut h, &mut t);
        if !p.is_null() {
            // Every byte the device says is there is read: a short or
            // freed buffer shows under the sanitizer.
            let bytes = w as usize * h as usize * DataType::from_code(t).map_or(0, DataType::size);
            let mapped = std::slice::from_raw_parts(p.cast::<u8>(), bytes);
            std::hint::black_box(mapped.iter().fold(0u8, |a, b| a ^ b));
            anariUnmapFrame(dev, f, channel.as_ptr());
        }
    }

    unsafe fn unset(&mut self) {
        let o = self.handle();
        let name = CString::new(*self.input.pick(&self.words.names)).unwrap_or_default();
        anariUnsetParameter(self.dev, o, name.as_ptr());
    }

    unsafe fn property(&mut self, wait: bool) {
        let o = self.handle();
        let mut out = [0u8; 64];
        let name = CString::new(*self.input.pick(&[
            "bounds",
            "duration",
            "numSamples",
            "renderProgress",
            "version",
            "extension",
            "subtypes.renderer",
        ]))
        .unwrap_or_default();
        let ty = *self.input.pick(&self.words.types);
        let size = (ty.size() as u64).min(64);
        anariGetProperty(
            self.dev,
            o,
            name.as_ptr(),
            ty as i32,
            out.as_mut_ptr().cast(),
            size,
            u32::from(wait),
        );
    }

    /// Releases one of the thread's own objects.
    unsafe fn release(&mut self) {
        if !self.objects.is_empty() {
            let i = usize::from(self.input.byte()) % self.objects.len();
            anariRelease(self.dev, self.objects.swap_remove(i));
        }
    }

    /// A frame gets the completion callback (and the callbacks' script
    /// grows by up to 31 bytes).
    unsafe fn completion_callback(&mut self) {
        let f = self.handle();
        let n = usize::from(self.input.byte() % 32);
        let script = self.input.take(n);
        callbacks().script.extend(script);
        let callback: sys::ANARIFrameCompletionCallback = Some(on_frame_done);
        anariSetParameter(
            self.dev,
            f,
            c"frameCompletionCallback".as_ptr(),
            DataType::FRAME_COMPLETION_CALLBACK as i32,
            (&callback as *const sys::ANARIFrameCompletionCallback).cast(),
        );
        anariSetParameter(
            self.dev,
            f,
            c"frameCompletionCallbackUserData".as_ptr(),
            DataType::VOID_POINTER as i32,
            std::ptr::null(),
        );
        anariCommitParameters(self.dev, f);
    }

    /// Retains the device or a handle for the callbacks, which own that
    /// reference from then on.
    unsafe fn hand_over(&mut self) {
        let h = if self.input.byte().is_multiple_of(4) {
            self.dev
        } else {
            self.handle()
        };
        anariRetain(self.dev, h);
        callbacks().owned.push(h as usize);
    }

    /// The device gets the status callback (and the script grows).
    unsafe fn status_callback(&mut self) {
        let n = usize::from(self.input.byte() % 32);
        let script = self.input.take(n);
        callbacks().script.extend(script);
        let callback: sys::ANARIStatusCallback = Some(on_status);
        anariSetParameter(
            self.dev,
            self.dev,
            c"statusCallback".as_ptr(),
            DataType::STATUS_CALLBACK as i32,
            (&callback as *const sys::ANARIStatusCallback).cast(),
        );
        anariCommitParameters(self.dev, self.dev);
    }
}

/// The second host thread: its own script, objects of its own (released
/// at its end) and the first thread's handles as they were when it
/// started, which it renders, queries, discards and sets but never
/// releases.
fn second_host(dev: usize, script: &[u8], words: &Words, shared: Vec<usize>) {
    let mut host = Host {
        input: Input(script),
        dev: dev as sys::ANARIDevice,
        words,
        objects: Vec::new(),
        shared,
    };
    // SAFETY: as in `capi`.
    unsafe {
        while !host.input.done() && host.objects.len() < 32 {
            match host.input.byte() % 9 {
                0 => host.create(),
                1 => host.set(),
                2 => {
                    let o = host.handle();
                    anariCommitParameters(host.dev, o);
                }
                3 => host.render(),
                4 => {
                    let wait = host.input.byte().is_multiple_of(2);
                    host.property(wait)
                }
                5 => {
                    let f = host.handle();
                    anariDiscardFrame(host.dev, f);
                }
                6 => host.release(),
                7 => {
                    let f = host.handle();
                    anariFrameReady(host.dev, f, 0);
                }
                _ => host.array(),
            }
        }
        for o in host.objects {
            anariRelease(host.dev, o);
        }
    }
}

/// A host driving the C API: objects of every kind and subtype (and
/// unknown ones), parameters of every name caveray knows (and others) set
/// with any type and bytes, arrays of any element type, commits, renders
/// of small frames (the harness keeps `size` to 64 x 64 so that each
/// input runs in milliseconds), discards and releases, in any order; a
/// frame completion callback and a status callback that call back into
/// the API (properties, waits, renders, discards, maps, releases of the
/// handles handed to them) as a script in the input says; and a second
/// host thread, with a script of its own, calling at the same time.
pub fn capi(data: &[u8]) {
    let lib = library();
    let words = Words::new();
    {
        let mut c = callbacks();
        c.script.clear();
        c.at = 0;
        c.owned.clear();
    }
    // SAFETY: every call gets valid pointers of the sizes its types need;
    // handles may be anything, which the device must survive.
    unsafe {
        assert!(!lib.is_null(), "the library does not load");
        let dev = anariNewDevice(lib, c"default".as_ptr());
        assert!(!dev.is_null(), "no device");
        anariSetParameter(
            dev,
            dev,
            c"backend".as_ptr(),
            DataType::STRING as i32,
            c"cpu".as_ptr().cast(),
        );
        anariCommitParameters(dev, dev);
        let objects = std::thread::scope(|scope| {
            let mut host = Host {
                input: Input(data),
                dev,
                words: &words,
                objects: Vec::new(),
                shared: Vec::new(),
            };
            let mut second = None;
            while !host.input.done() && host.objects.len() < 64 {
                match host.input.byte() % 14 {
                    0 | 1 => host.create(),
                    2 | 3 => host.set(),
                    4 => {
                        let o = host.handle();
                        anariCommitParameters(dev, o);
                    }
                    5 => host.array(),
                    6 => host.render(),
                    7 => host.unset(),
                    8 => host.property(true),
                    9 => host.release(),
                    10 => host.completion_callback(),
                    11 => host.hand_over(),
                    12 => host.status_callback(),
                    _ if second.is_none() => {
                        let n = usize::from(host.input.byte()) * 2;
                        let script = host.input.take(n);
                        let shared = host.objects.iter().map(|&o| o as usize).collect();
                        let (dev, words) = (dev as usize, &words);
                        second =
                            Some(scope.spawn(move || second_host(dev, &script, words, shared)));
                    }
                    _ => {}
                }
            }
            host.objects
        });
        // The callbacks do nothing more; what they were handed and did not
        // release goes now.
        let handed = {
            let mut c = callbacks();
            c.at = c.script.len();
            std::mem::take(&mut c.owned)
        };
        for h in handed {
            anariRelease(dev, h as sys::ANARIObject);
        }
        for o in objects {
            anariRelease(dev, o);
        }
        anariRelease(dev, dev);
        // The device's teardown may go on after its release returns;
        // unloading waits for it, so that each input ends with all it
        // made freed (the leak check runs between inputs).
        anariUnloadLibrary(lib);
    }
}

/// A VTK unstructured grid (`.vtu` or legacy `.vtk`): any bytes.
pub fn vtk_mesh(data: &[u8]) {
    if let Ok(m) = parse_vtk_mesh(data, "fuzz.vtu", None) {
        let (lo, hi) = m.mesh.bounds();
        let _ = m.mesh.sample(0.5 * (lo + hi));
    }
}

/// An `unstructured` field built through the C API from the input: the
/// first bytes pick how many positions, indices and cells there are and
/// the element types of the index, cell and data arrays; the rest fill
/// the arrays. The field is committed, put in a volume and rendered on a
/// small frame.
#[allow(clippy::too_many_lines)]
pub fn unstructured(data: &[u8]) {
    let mut input = Input(data);
    let mut byte = || input.take(1).first().copied().unwrap_or(0);
    let (positions_byte, indices_byte, cells_byte, choice) = (byte(), byte(), byte(), byte());
    let positions = usize::from(positions_byte % 24) + 1;
    let indices = usize::from(indices_byte) % 48 + 1;
    let cells = usize::from(cells_byte % 8) + 1;
    let index_type = if choice & 1 == 0 {
        DataType::UINT32
    } else {
        DataType::UINT64
    };
    let type_type = if choice & 2 == 0 {
        DataType::UINT8
    } else {
        DataType::UINT32
    };
    let data_type = [
        DataType::FLOAT32,
        DataType::FLOAT64,
        DataType::UFIXED8,
        DataType::UFIXED16,
        DataType::FIXED16,
    ][usize::from(choice >> 2) % 5];
    let per_cell = choice & 0x80 != 0;
    let mut fill = |n: usize| -> Vec<u8> {
        let mut v = input.take(n).to_vec();
        v.resize(n, 0);
        v
    };
    // Positions as small floats from bytes, so that cells have volume.
    let position_bytes: Vec<u8> = fill(3 * positions)
        .iter()
        .flat_map(|&b| (f32::from(b % 16) * 0.25).to_ne_bytes())
        .collect();
    let index_bytes: Vec<u8> = fill(indices)
        .iter()
        .flat_map(|&b| {
            let v = u64::from(b % (positions as u8 + 2));
            if index_type == DataType::UINT32 {
                (v as u32).to_ne_bytes().to_vec()
            } else {
                v.to_ne_bytes().to_vec()
            }
        })
        .collect();
    let starts: Vec<u8> = fill(cells)
        .iter()
        .scan(0u64, |at, &b| {
            let here = *at;
            *at += u64::from(b % 9);
            Some(here)
        })
        .flat_map(|v| {
            if index_type == DataType::UINT32 {
                (v as u32).to_ne_bytes().to_vec()
            } else {
                v.to_ne_bytes().to_vec()
            }
        })
        .collect();
    let types: Vec<u8> = fill(cells)
        .iter()
        .flat_map(|&b| {
            let code = [10u32, 12, 13, 14, 11, 7][usize::from(b) % 6];
            if type_type == DataType::UINT8 {
                vec![code as u8]
            } else {
                code.to_ne_bytes().to_vec()
            }
        })
        .collect();
    let values = if per_cell { cells } else { positions };
    let value_bytes = fill(values * data_type.size());
    let Some(dev) = cpu_device() else {
        return;
    };
    let array = |bytes: &[u8], ty: DataType, n: usize| array1d(dev, bytes, ty, n);
    // SAFETY: every array's memory holds its count of its element type
    // and outlives the device's copy of it (arrays are copied at commit).
    unsafe {
        let field = anariNewSpatialField(dev, c"unstructured".as_ptr());
        let arrays = [
            (
                c"vertex.position",
                array(&position_bytes, DataType::FLOAT32_VEC3, positions),
            ),
            (c"index", array(&index_bytes, index_type, indices)),
            (c"cell.index", array(&starts, index_type, cells)),
            (c"cell.type", array(&types, type_type, cells)),
            (
                if per_cell {
                    c"cell.data"
                } else {
                    c"vertex.data"
                },
                array(&value_bytes, data_type, values),
            ),
        ];
        for (name, a) in &arrays {
            anariSetParameter(
                dev,
                field,
                name.as_ptr(),
                DataType::ARRAY1D as i32,
                (a as *const sys::ANARIArray1D).cast(),
            );
        }
        anariCommitParameters(dev, field);
        render_small(dev, field);
        for (_, a) in arrays {
            anariRelease(dev, a);
        }
        anariRelease(dev, field);
        anariRelease(dev, dev);
    }
}

/// A device of the library on the CPU backend, `None` if none is made.
fn cpu_device() -> Option<sys::ANARIDevice> {
    let lib = library();
    // SAFETY: the library is loaded; the strings are NUL-terminated.
    unsafe {
        let dev = anariNewDevice(lib, c"default".as_ptr());
        if dev.is_null() {
            return None;
        }
        anariSetParameter(
            dev,
            dev,
            c"backend".as_ptr(),
            DataType::STRING as i32,
            c"cpu".as_ptr().cast(),
        );
        anariCommitParameters(dev, dev);
        Some(dev)
    }
}

/// An ARRAY1D of `n` `ty`s over `bytes`, which must hold them and
/// outlive the array's use.
fn array1d(dev: sys::ANARIDevice, bytes: &[u8], ty: DataType, n: usize) -> sys::ANARIArray1D {
    // SAFETY: `dev` is live; the caller keeps `bytes` while the array is.
    unsafe {
        anariNewArray1D(
            dev,
            bytes.as_ptr().cast(),
            None,
            std::ptr::null(),
            ty as i32,
            n as u64,
        )
    }
}

/// Renders `field` in a volume on a small frame of `dev`, releasing what
/// it made.
///
/// # Safety
/// `dev` and `field` are live handles of the library.
unsafe fn render_small(dev: sys::ANARIDevice, field: sys::ANARISpatialField) {
    unsafe {
        let volume = anariNewVolume(dev, c"transferFunction1D".as_ptr());
        anariSetParameter(
            dev,
            volume,
            c"value".as_ptr(),
            DataType::SPATIAL_FIELD as i32,
            (&field as *const sys::ANARISpatialField).cast(),
        );
        anariCommitParameters(dev, volume);
        let list = anariNewArray1D(
            dev,
            (&volume as *const sys::ANARIVolume).cast(),
            None,
            std::ptr::null(),
            DataType::VOLUME as i32,
            1,
        );
        let world = anariNewWorld(dev);
        anariSetParameter(
            dev,
            world,
            c"volume".as_ptr(),
            DataType::ARRAY1D as i32,
            (&list as *const sys::ANARIArray1D).cast(),
        );
        anariCommitParameters(dev, world);
        let frame = anariNewFrame(dev);
        let size = [8u32, 8];
        anariSetParameter(
            dev,
            frame,
            c"size".as_ptr(),
            DataType::UINT32_VEC2 as i32,
            size.as_ptr().cast(),
        );
        let renderer = anariNewRenderer(dev, c"default".as_ptr());
        anariCommitParameters(dev, renderer);
        let camera = anariNewCamera(dev, c"perspective".as_ptr());
        let eye = [2.0f32, 2.0, 8.0];
        anariSetParameter(
            dev,
            camera,
            c"position".as_ptr(),
            DataType::FLOAT32_VEC3 as i32,
            eye.as_ptr().cast(),
        );
        anariCommitParameters(dev, camera);
        anariSetParameter(
            dev,
            frame,
            c"world".as_ptr(),
            DataType::WORLD as i32,
            (&world as *const sys::ANARIWorld).cast(),
        );
        anariSetParameter(
            dev,
            frame,
            c"renderer".as_ptr(),
            DataType::RENDERER as i32,
            (&renderer as *const sys::ANARIRenderer).cast(),
        );
        anariSetParameter(
            dev,
            frame,
            c"camera".as_ptr(),
            DataType::CAMERA as i32,
            (&camera as *const sys::ANARICamera).cast(),
        );
        anariCommitParameters(dev, frame);
        anariRenderFrame(dev, frame);
        anariFrameReady(dev, frame, sys::ANARI_WAIT as u32);
        for o in [volume, list, world, frame, renderer, camera] {
            anariRelease(dev, o);
        }
    }
}

/// An `amr` field's block tables through the C API: the first bytes pick
/// the levels, the blocks and the form (OpenCOVER's `cellWidth` and an
/// array per block, or visionaray's `refinementRatio` and one `data`);
/// each block's level and bounds (small, perhaps negative, perhaps
/// empty) and its array's element type and size (sometimes not its
/// bounds') come next, the rest fill the values. The field is committed,
/// put in a volume and rendered on a small frame.
pub fn amr(data: &[u8]) {
    let mut input = Input(data);
    let levels = usize::from(input.byte() % 4) + 1;
    let blocks = usize::from(input.byte() % 6) + 1;
    let form = input.byte();
    let widths: Vec<f32> = (0..levels)
        .map(|_| f32::from(input.byte() % 9) * 0.5)
        .collect();
    let ratio = u32::from(input.byte() % 5);
    let mut bounds = Vec::new();
    let mut block_levels = Vec::new();
    let mut sizes = Vec::new();
    for _ in 0..blocks {
        block_levels.push(i32::from(input.byte() % 6) - 1);
        let mut b = [0i32; 6];
        for v in &mut b {
            *v = i32::from(input.byte() % 16) - 4;
        }
        bounds.extend(b);
        let size = [0, 1, 2].map(|k| (b[k + 3] - b[k] + 1).clamp(0, 12) as u64);
        // Now and then an array of another size than the bounds hold.
        let wrong = input.byte();
        sizes.push(if wrong < 16 {
            [size[0] + u64::from(wrong % 3), size[1], size[2]]
        } else {
            size
        });
    }
    let element = *input.pick(&[
        DataType::FLOAT32,
        DataType::FLOAT64,
        DataType::UFIXED8,
        DataType::FIXED16,
        DataType::INT32,
    ]);
    let Some(dev) = cpu_device() else {
        return;
    };
    let list = |bytes: &[u8], ty: DataType, n: usize| array1d(dev, bytes, ty, n);
    // SAFETY: every array's memory holds its count of its element type
    // and outlives the calls that read it (arrays are read at commit).
    unsafe {
        let mut fill = |n: u64| -> Vec<u8> {
            let n = (n as usize).min(1 << 16);
            let mut v = input.take(n);
            v.resize(n, 0x3f);
            v
        };
        let field = anariNewSpatialField(dev, c"amr".as_ptr());
        let mut arrays = Vec::new();
        let set = |name: &std::ffi::CStr, a: sys::ANARIArray1D| {
            anariSetParameter(
                dev,
                field,
                name.as_ptr(),
                DataType::ARRAY1D as i32,
                (&a as *const sys::ANARIArray1D).cast(),
            );
            a
        };
        let bound_bytes: Vec<u8> = bounds.iter().flat_map(|v| v.to_ne_bytes()).collect();
        let level_bytes: Vec<u8> = block_levels.iter().flat_map(|v| v.to_ne_bytes()).collect();
        arrays.push(set(
            c"block.bounds",
            list(&bound_bytes, DataType::INT32_BOX3, blocks),
        ));
        arrays.push(set(
            c"block.level",
            list(&level_bytes, DataType::INT32, blocks),
        ));
        let mut blocks_made = Vec::new();
        let mut kept = Vec::new();
        if form & 1 == 0 {
            let width_bytes: Vec<u8> = widths.iter().flat_map(|v| v.to_ne_bytes()).collect();
            arrays.push(set(
                c"cellWidth",
                list(&width_bytes, DataType::FLOAT32, levels),
            ));
            // Shared arrays read the host's memory until released.
            kept.push(width_bytes);
            for size in &sizes {
                let n = size.iter().product::<u64>();
                let bytes = fill(n * element.size() as u64);
                let a = anariNewArray3D(
                    dev,
                    bytes.as_ptr().cast(),
                    None,
                    std::ptr::null(),
                    element as i32,
                    size[0],
                    size[1],
                    size[2],
                );
                kept.push(bytes);
                blocks_made.push(a as usize);
            }
            let handles: Vec<u8> = blocks_made.iter().flat_map(|h| h.to_ne_bytes()).collect();
            let declared = if form & 2 == 0 {
                DataType::ARRAY1D
            } else {
                DataType::ARRAY3D
            };
            arrays.push(set(
                c"block.data",
                list(&handles, declared, blocks_made.len()),
            ));
            kept.push(handles);
        } else {
            anariSetParameter(
                dev,
                field,
                c"refinementRatio".as_ptr(),
                DataType::UINT32 as i32,
                (&ratio as *const u32).cast(),
            );
            let n: u64 = sizes.iter().map(|s| s.iter().product::<u64>()).sum();
            let bytes = fill(n * element.size() as u64);
            arrays.push(set(c"data", list(&bytes, element, n as usize)));
            kept.push(bytes);
        }
        anariCommitParameters(dev, field);
        render_small(dev, field);
        for a in arrays {
            anariRelease(dev, a);
        }
        for h in blocks_made {
            anariRelease(dev, h as sys::ANARIArray3D);
        }
        anariRelease(dev, field);
        anariRelease(dev, dev);
        drop(kept);
    }
}

/// The NanoVDB grid the `nanovdb` target starts from: the smallest one
/// with a node of every kind, as the NanoVDB library wrote it
/// (`tests/writers/nanovdb_grids.cpp DIR seed`), gzipped.
fn nanovdb_seed() -> Vec<u8> {
    use std::io::Read;
    let gz: &[u8] = include_bytes!("../seeds/nanovdb.blob.gz");
    let mut blob = Vec::new();
    flate2::read::GzDecoder::new(gz)
        .read_to_end(&mut blob)
        .expect("the committed seed unpacks");
    blob
}

/// A `nanovdb` field: the first byte picks the filter and whether the
/// rest is the blob itself or patches to the seed grid (each an offset
/// (u32), a length (1 to 8) and that many bytes; then perhaps a cut),
/// so that inputs reach past the header checks into the tree's walk and
/// the samples.
pub fn nanovdb(data: &[u8]) {
    let mut input = Input(data);
    let mode = input.byte();
    let blob = if mode & 1 == 0 {
        input.take(usize::MAX)
    } else {
        let mut blob = nanovdb_seed();
        while !input.done() {
            let at = u32::from_le_bytes([input.byte(), input.byte(), input.byte(), input.byte()]);
            let len = usize::from(input.byte() % 8) + 1;
            let at = at as usize % blob.len();
            for (k, b) in input.take(len).into_iter().enumerate() {
                if let Some(slot) = blob.get_mut(at + k) {
                    *slot = b;
                }
            }
        }
        if mode & 8 != 0 {
            let keep = blob.len() * usize::from(mode >> 4) / 16;
            blob.truncate(keep);
        }
        blob
    };
    let filter =
        [None, Some(c"linear"), Some(c"nearest"), Some(c"cubic")][usize::from(mode >> 1 & 3)];
    let Some(dev) = cpu_device() else {
        return;
    };
    // SAFETY: the array's memory (`blob`) outlives the field's commit,
    // where it is read; every handle is released.
    unsafe {
        let field = anariNewSpatialField(dev, c"nanovdb".as_ptr());
        let array = array1d(dev, &blob, DataType::UINT8, blob.len());
        anariSetParameter(
            dev,
            field,
            c"data".as_ptr(),
            DataType::ARRAY1D as i32,
            (&array as *const sys::ANARIArray1D).cast(),
        );
        if let Some(filter) = filter {
            anariSetParameter(
                dev,
                field,
                c"filter".as_ptr(),
                DataType::STRING as i32,
                filter.as_ptr().cast(),
            );
        }
        anariCommitParameters(dev, field);
        render_small(dev, field);
        anariRelease(dev, array);
        anariRelease(dev, field);
        anariRelease(dev, dev);
    }
    drop(blob);
}
