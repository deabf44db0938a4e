//! DICOM series: a folder of slices (or one of its files, which stands
//! for its series), a frame a file or enhanced multi-frame files whose
//! functional groups place each frame. dicom-rs parses the files
//! (`dicom-object`) and decodes their frames (`dicom-pixeldata`: deflated,
//! RLE and JPEG in pure Rust, JPEG 2000 by OpenJPEG's C, JPEG-LS refused
//! by name). Slices are ordered along their normal, not by
//! file name or instance number, which exporters get wrong, and placed in
//! RAS+ (DICOM's patient space is LPS). Values are the modality's
//! (Hounsfield units for CT), kept in their stored type where one rescale
//! holds for the series.

mod header;
mod series;

use std::io::Read;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use dicom_core::dictionary::{DataDictionary, DataDictionaryEntry};
use dicom_core::Tag;
use dicom_dictionary_std::{tags, StandardDataDictionary};
use dicom_encoding::transfer_syntax::TransferSyntaxIndex;
use dicom_object::{FileDicomObject, InMemDicomObject, OpenFileOptions};
use dicom_pixeldata::PixelDecoder;
use dicom_transfer_syntax_registry::TransferSyntaxRegistry;
use serde_json::Value;

use self::header::{lengths_fit, slices_of};
use self::series::{assemble, Slice};
use super::stored::ZLIB_MAX_RATIO;
use super::{bad, files, format::VolumeFormat, volume_file::VolumeFile, DataError};

type Object = FileDicomObject<InMemDicomObject>;

/// Files of a folder looked at: a series of more slices than this is a
/// stack no scanner writes to one folder.
const MAX_FILES: usize = 1 << 16;

/// Loads the series at `path`: a folder (its largest series, where it
/// holds several) or one of its files (that file's series).
pub fn load_dicom(path: &Path) -> Result<VolumeFile, DataError> {
    let (folder, chosen) = match path.is_dir() {
        true => (path, None),
        false => {
            let series = read_slices(path)?.first().map(|s| s.series.clone());
            let parent = path.parent().filter(|p| !p.as_os_str().is_empty());
            (parent.unwrap_or(Path::new(".")), series)
        }
    };
    let name = folder.display().to_string();
    let mut series: Vec<(String, Vec<Slice>)> = Vec::new();
    let mut skipped = Vec::new();
    // Other files (a DICOMDIR, a report, a thumbnail) share series folders;
    // a broken slice shows as a gap when the series is checked.
    for file in folder_files(folder, &name)? {
        for slice in read_slices(&file)
            .map_err(|e| skipped.push(e))
            .unwrap_or_default()
        {
            match series.iter_mut().find(|(uid, _)| *uid == slice.series) {
                Some((_, members)) => members.push(slice),
                None => series.push((slice.series.clone(), vec![slice])),
            }
        }
    }
    let count = series.len();
    let (uid, members) = match chosen {
        Some(uid) => series.into_iter().find(|(u, _)| *u == uid),
        None => series.into_iter().max_by_key(|(_, m)| m.len()),
    }
    .ok_or_else(|| {
        // A slice with a field at fault says so itself; files that are no
        // DICOM at all say the folder holds no series.
        let at_fault =
            |e: &DataError| matches!(e, DataError::Header { field, .. } if field != "file");
        match (skipped.iter().position(at_fault), skipped.first()) {
            (Some(i), _) => skipped.swap_remove(i),
            (None, first) => bad(
                &name,
                "files",
                match first {
                    Some(e) => format!("no DICOM image slices in the folder (the first file: {e})"),
                    None => "no files in the folder".into(),
                },
            ),
        }
    })?;
    let mut file = assemble(members, &name, |slice| {
        let bytes = file_bytes(&slice.file)?;
        let object = open_object(&bytes, &slice.file.display().to_string(), true)?;
        decode(&object, slice, bytes.len())
    })?;
    file.details.insert(0, ("series", Value::from(uid)));
    file.details.push(("series_in_folder", Value::from(count)));
    file.details
        .push(("files_skipped", Value::from(skipped.len())));
    if !path.is_dir() {
        file.format = VolumeFormat::Dicom;
    }
    Ok(file)
}

/// One DICOM file held in memory, read as a series of its own (for the
/// fuzz target): the same checks and decoding as a folder's.
pub fn parse_dicom(bytes: &[u8], name: &str) -> Result<VolumeFile, DataError> {
    let object = open_object(bytes, name, true)?;
    let slices = slices_of(&object, Path::new(name))?;
    assemble(slices, name, |first| decode(&object, first, bytes.len()))
}

fn io(name: &str) -> impl Fn(std::io::Error) -> DataError + '_ {
    move |source| DataError::Io {
        file: name.to_string(),
        source,
    }
}

/// The regular files of `folder`, sorted by name.
fn folder_files(folder: &Path, name: &str) -> Result<Vec<PathBuf>, DataError> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(folder).map_err(io(name))?.flatten() {
        if entry.file_type().is_ok_and(|t| t.is_file()) {
            if found.len() == MAX_FILES {
                let why = format!("more than {MAX_FILES} files; caveray reads one series a folder");
                return Err(bad(name, "files", why));
            }
            found.push(entry.path());
        }
    }
    found.sort();
    Ok(found)
}

/// The slices (frames) of `file`, its pixels left unread.
fn read_slices(file: &Path) -> Result<Vec<Slice>, DataError> {
    let object = open_object(&file_bytes(file)?, &file.display().to_string(), false)?;
    slices_of(&object, file)
}

/// The whole of `file`, where it is a DICOM file (`DICM` after its
/// preamble): a large file beside the slices is not read to find it is
/// not one.
fn file_bytes(file: &Path) -> Result<Vec<u8>, DataError> {
    let name = file.display().to_string();
    let (mut handle, len) = files::open_regular(file).map_err(io(&name))?;
    let mut head = [0u8; 132];
    if len < 132 || handle.read_exact(&mut head).is_err() || &head[128..] != b"DICM" {
        let why = "not a DICOM file (no DICM after a 128-byte preamble)";
        return Err(bad(&name, "file", why.into()));
    }
    let (handle, len) = files::open_regular(file).map_err(io(&name))?;
    files::read_len(handle, len).map_err(io(&name))
}

/// The DICOM object of `bytes` (a whole file from its preamble), its pixel
/// data read `with_pixels`; its lengths are checked first.
fn open_object(bytes: &[u8], name: &str, with_pixels: bool) -> Result<Object, DataError> {
    let fault =
        |(tag, why): (Option<Tag>, String)| bad(name, &tag.map_or("file".into(), tag_name), why);
    let uid = lengths_fit(bytes).map_err(fault)?;
    let why = match TransferSyntaxRegistry.get(&uid) {
        // No pure-Rust decoder exists for JPEG-LS.
        Some(ts) if uid.starts_with("1.2.840.10008.1.2.4.8") => format!(
            "{} ({uid}) has no decoder in pure Rust, and caveray links no C++ codec: \
             decompress the series with dcmtk's dcmdjpls or gdcmconv --raw",
            ts.name()
        ),
        Some(ts) if !ts.can_decode_all() => format!("{} ({uid}) is not decoded", ts.name()),
        Some(_) => String::new(),
        None => format!("{uid} is not a transfer syntax caveray knows"),
    };
    if !why.is_empty() {
        return Err(bad(name, "TransferSyntaxUID", why));
    }
    let options = match with_pixels {
        true => OpenFileOptions::new(),
        false => OpenFileOptions::new().read_until(tags::PIXEL_DATA),
    };
    let object = options.from_reader(&bytes[128..]);
    object.map_err(|e| bad(name, "file", one_line(&e)))
}

/// An error and its causes on one line.
fn one_line(e: &dyn std::error::Error) -> String {
    let (mut line, mut cause) = (e.to_string(), e.source());
    while let Some(c) = cause {
        (line, cause) = (format!("{line}: {c}"), c.source());
    }
    line
}

/// The name of `tag` in the standard dictionary, else its numbers.
fn tag_name(tag: Tag) -> String {
    let entry = StandardDataDictionary.by_tag(tag);
    entry.map_or(tag.to_string(), |e| e.alias().to_string())
}

/// Every frame of `object` decoded, samples in the machine's byte order;
/// `slice` (one of its frames) gives their size.
fn decode(object: &Object, slice: &Slice, file_len: usize) -> Result<Vec<u8>, DataError> {
    let name = slice.file.display().to_string();
    let frames = object.get(tags::NUMBER_OF_FRAMES);
    let frames = frames.and_then(|e| e.to_int::<u64>().ok()).unwrap_or(1);
    let bytes = frames.saturating_mul(slice.frame_len() as u64);
    // No codec here compresses beyond what deflate can: a file that claims
    // more is refused before a decoder allocates for it.
    if bytes / ZLIB_MAX_RATIO as u64 > file_len as u64 {
        let why = format!("{frames} frames of {bytes} bytes in all from a file of {file_len}");
        return Err(bad(&name, "Rows", why));
    }
    // dicom-rs's RLE adapter reserves as many segment offsets as a
    // fragment's first four bytes say, and an allocation that fails aborts
    // the process: its header is 64 bytes of at most 15 (PS3.5 G.5).
    if object.meta().transfer_syntax() == "1.2.840.10008.1.2.5" {
        let fragments = object.get(tags::PIXEL_DATA).and_then(|e| e.fragments());
        let segments = |f: &Vec<u8>| {
            f.get(..4)
                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        };
        if let Some(f) = fragments
            .unwrap_or_default()
            .iter()
            .find(|f| f.len() < 64 || segments(f) > Some(15))
        {
            let why = format!(
                "an RLE fragment of {} bytes claims {:?} segments",
                f.len(),
                segments(f)
            );
            return Err(bad(&name, "PixelData", why));
        }
    }
    // A codec that panics on a broken frame must not take the host down:
    // its panic is this file's error.
    let decoded = catch_unwind(AssertUnwindSafe(|| {
        object.decode_pixel_data().map(|d| d.into_data())
    }));
    let why = match decoded {
        Ok(Ok(data)) if data.len() as u64 >= bytes => return Ok(data),
        Ok(Ok(data)) => format!(
            "{} bytes decoded where {frames} frames need {bytes}",
            data.len()
        ),
        Ok(Err(e)) => one_line(&e),
        Err(_) => "its decoder failed".into(),
    };
    Err(bad(&name, "PixelData", why))
}
