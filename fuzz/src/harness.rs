//! What each fuzz target feeds its input to. Kept apart from libFuzzer so
//! that `tests/fuzz_corpus/main.rs` replays the committed corpus and every
//! input that once crashed through the same code on stable Rust.
//! Every function here must return, whatever its input: a panic, abort,
//! hang or out-of-memory is a bug in caveray.

use std::ffi::{c_void, CString};
use std::path::Path;
use std::sync::OnceLock;

use anari_library_caveray::capi::entry_points::*;
use anari_library_caveray::capi::sys;
use anari_library_caveray::cave::{MultiViewDisplay, Rig};
use anari_library_caveray::data::{parse_paraview, parse_raw, Manifest, VoxelType};
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
/// bytes after it) read as the manifest's first entry describes it.
pub fn raw_manifest(data: &[u8]) {
    let split = data.iter().position(|&b| b == 0).unwrap_or(data.len());
    let (text, bytes) = (&data[..split], data.get(split + 1..).unwrap_or(&[]));
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

/// The library, loaded once per process as a host loads it.
fn library() -> sys::ANARILibrary {
    static LIBRARY: OnceLock<usize> = OnceLock::new();
    *LIBRARY.get_or_init(|| {
        // SAFETY: a valid name and callback.
        unsafe { anariLoadLibrary(c"caveray".as_ptr(), Some(quiet), std::ptr::null()) as usize }
    }) as sys::ANARILibrary
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

/// A host driving the C API: objects of every kind and subtype (and
/// unknown ones), parameters of every name caveray knows (and others) set
/// with any type and bytes, arrays of any element type, commits, renders
/// of small frames (the harness keeps `size` to 64 x 64 so that each
/// input runs in milliseconds), discards and releases, in any order.
pub fn capi(data: &[u8]) {
    let mut input = Input(data);
    let lib = library();
    let types = settable();
    let mut names: Vec<&str> = SUBTYPES
        .iter()
        .flat_map(|s| s.params.iter().map(|p| p.name))
        .filter(|n| *n != "size")
        .collect();
    names.extend(["", "name", "ünïcode", "channel.normal"]);
    let mut subtypes: Vec<&str> = SUBTYPES.iter().map(|s| s.subtype).collect();
    subtypes.extend(["", "pathtracer", "unknown"]);
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
        let mut objects: Vec<sys::ANARIObject> = Vec::new();
        let handle = |input: &mut Input, objects: &[sys::ANARIObject]| -> sys::ANARIObject {
            match input.byte() {
                255 => 0x1234 as sys::ANARIObject,
                254 => std::ptr::null_mut(),
                i if objects.is_empty() => i as usize as sys::ANARIObject,
                i => objects[usize::from(i) % objects.len()],
            }
        };
        while !input.done() && objects.len() < 64 {
            match input.byte() % 10 {
                0 | 1 => {
                    let sub = CString::new(*input.pick(&subtypes)).unwrap_or_default();
                    let s = sub.as_ptr();
                    let o = match input.byte() % 11 {
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
                        objects.push(o);
                    }
                }
                2 | 3 => {
                    let o = handle(&mut input, &objects);
                    let name = CString::new(*input.pick(&names)).unwrap_or_default();
                    let ty = *input.pick(&types);
                    if ty == DataType::STRING {
                        let len = usize::from(input.byte() % 16);
                        let text = CString::new(
                            input
                                .take(len)
                                .into_iter()
                                .filter(|&b| b != 0)
                                .collect::<Vec<u8>>(),
                        )
                        .unwrap_or_default();
                        anariSetParameter(dev, o, name.as_ptr(), ty as i32, text.as_ptr().cast());
                    } else if ty.is_object() {
                        let h = handle(&mut input, &objects);
                        anariSetParameter(
                            dev,
                            o,
                            name.as_ptr(),
                            ty as i32,
                            (&h as *const sys::ANARIObject).cast(),
                        );
                    } else {
                        let mut mem = input.take(ty.size());
                        mem.resize(ty.size().max(1), 0);
                        anariSetParameter(dev, o, name.as_ptr(), ty as i32, mem.as_ptr().cast());
                    }
                }
                4 => {
                    let o = handle(&mut input, &objects);
                    anariCommitParameters(dev, o);
                }
                5 => {
                    let element = *input.pick(&types);
                    let dims =
                        [input.byte() % 17, input.byte() % 17, input.byte() % 17].map(u64::from);
                    let rank = usize::from(input.byte() % 3) + 1;
                    let a = match rank {
                        1 => anariNewArray1D(
                            dev,
                            std::ptr::null(),
                            None,
                            std::ptr::null(),
                            element as i32,
                            dims[0],
                        ),
                        2 => anariNewArray2D(
                            dev,
                            std::ptr::null(),
                            None,
                            std::ptr::null(),
                            element as i32,
                            dims[0],
                            dims[1],
                        ),
                        _ => anariNewArray3D(
                            dev,
                            std::ptr::null(),
                            None,
                            std::ptr::null(),
                            element as i32,
                            dims[0],
                            dims[1],
                            dims[2],
                        ),
                    };
                    if !a.is_null() {
                        let p = anariMapArray(dev, a);
                        if !p.is_null() && !element.is_object() {
                            let count: u64 = dims[..rank].iter().product();
                            let bytes = count as usize * element.size();
                            let fill = input.take(bytes);
                            std::ptr::copy_nonoverlapping(
                                fill.as_ptr(),
                                p.cast::<u8>(),
                                fill.len(),
                            );
                        }
                        anariUnmapArray(dev, a);
                        objects.push(a);
                    }
                }
                6 => {
                    let f = handle(&mut input, &objects);
                    let size = [
                        u32::from(input.byte() % 64) + 1,
                        u32::from(input.byte() % 64) + 1,
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
                    if input.byte() % 4 == 0 {
                        anariDiscardFrame(dev, f);
                    }
                    anariFrameReady(dev, f, sys::ANARIWaitMask::from(1u32));
                    let (mut w, mut h, mut t) = (0u32, 0u32, 0i32);
                    let channel = if input.byte() % 2 == 0 {
                        c"channel.color"
                    } else {
                        c"channel.depth"
                    };
                    let p = anariMapFrame(dev, f, channel.as_ptr(), &mut w, &mut h, &mut t);
                    if !p.is_null() {
                        anariUnmapFrame(dev, f, channel.as_ptr());
                    }
                }
                7 => {
                    let o = handle(&mut input, &objects);
                    let name = CString::new(*input.pick(&names)).unwrap_or_default();
                    anariUnsetParameter(dev, o, name.as_ptr());
                }
                8 => {
                    let o = handle(&mut input, &objects);
                    let mut out = [0u8; 64];
                    let name = CString::new(*input.pick(&[
                        "bounds",
                        "duration",
                        "numSamples",
                        "renderProgress",
                        "version",
                        "extension",
                        "subtypes.renderer",
                    ]))
                    .unwrap_or_default();
                    let ty = *input.pick(&types);
                    let size = (ty.size() as u64).min(64);
                    anariGetProperty(
                        dev,
                        o,
                        name.as_ptr(),
                        ty as i32,
                        out.as_mut_ptr().cast(),
                        size,
                        1,
                    );
                }
                _ => {
                    if !objects.is_empty() {
                        let i = usize::from(input.byte()) % objects.len();
                        anariRelease(dev, objects.swap_remove(i));
                    }
                }
            }
        }
        for o in objects {
            anariRelease(dev, o);
        }
        anariRelease(dev, dev);
    }
}
