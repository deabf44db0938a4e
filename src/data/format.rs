//! Volume file formats caveray recognises, so that each file goes to its
//! own reader (and a gzipped raw file is refused by name) instead of being
//! taken for a headerless raw file of the wrong size. Known by content
//! where a format has a signature at a fixed place, else by file name.

use std::io::Read;
use std::path::Path;

use super::files;

/// Bytes looked at: every signature below lies within them.
pub const SNIFF_BYTES: usize = 512;

/// Entries of a folder looked at for DICOM slices: a series has its
/// slices side by side, so the first few tell.
const FOLDER_ENTRIES: usize = 64;

/// A format with a header, or a compression.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VolumeFormat {
    /// `NRRD000n` magic (`.nrrd`, or a detached `.nhdr` header).
    Nrrd,
    /// NIfTI-1 (`sizeof_hdr` 348, magic `n+1`/`ni1`) or NIfTI-2; `.nii`,
    /// `.nii.gz`.
    Nifti,
    /// ITK MetaImage text header (`ObjectType`, `NDims`, ...): `.mha`, `.mhd`.
    MetaImage,
    /// Legacy VTK (`# vtk DataFile`): `.vtk`.
    VtkLegacy,
    /// VTK XML (`<VTKFile`): `.vti` and the other XML data sets.
    VtkXml,
    /// One DICOM file (`DICM` at byte 128): a slice of a series.
    Dicom,
    /// A folder of DICOM slices.
    DicomSeries,
    /// gzip-compressed (`1f 8b`), of whatever is inside.
    Gzip,
}

impl VolumeFormat {
    /// What the format is called, as its users call it.
    pub fn name(self) -> &'static str {
        match self {
            VolumeFormat::Nrrd => "NRRD",
            VolumeFormat::Nifti => "NIfTI",
            VolumeFormat::MetaImage => "MetaImage",
            VolumeFormat::VtkLegacy => "legacy VTK",
            VolumeFormat::VtkXml => "VTK XML",
            VolumeFormat::Dicom | VolumeFormat::DicomSeries => "DICOM",
            VolumeFormat::Gzip => "gzip",
        }
    }

    /// What `path` is, if it is a file or folder in a format recognised
    /// here; `None` for anything else (a raw file, a missing path, a FIFO
    /// or device, which are never opened, or a folder without DICOM).
    pub fn of(path: &Path) -> Option<Self> {
        let meta = std::fs::metadata(path).ok()?;
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().to_lowercase())
            .unwrap_or_default();
        if meta.is_dir() {
            return dicom_folder(path).then_some(VolumeFormat::DicomSeries);
        }
        if !meta.is_file() {
            return None;
        }
        // An unreadable file is judged by its name; reading it as raw
        // then reports why it cannot be read.
        sniff(&name, &head(path).unwrap_or_default())
    }
}

/// File name endings of the formats, lower case.
const EXTENSIONS: &[(&str, VolumeFormat)] = &[
    (".nrrd", VolumeFormat::Nrrd),
    (".nhdr", VolumeFormat::Nrrd),
    (".nii", VolumeFormat::Nifti),
    (".mha", VolumeFormat::MetaImage),
    (".mhd", VolumeFormat::MetaImage),
    (".vtk", VolumeFormat::VtkLegacy),
    (".vti", VolumeFormat::VtkXml),
    (".dcm", VolumeFormat::Dicom),
    (".dicom", VolumeFormat::Dicom),
];

/// Raw files go by these names; only a signature no raw volume has by
/// chance overrides them.
const RAW_EXTENSIONS: &[&str] = &[".raw", ".dat", ".bin", ".img", ".vol"];

/// Keys a MetaImage header starts with (it may list them in any order).
const META_IMAGE_KEYS: &[&str] = &[
    "ObjectType",
    "ObjectSubType",
    "NDims",
    "DimSize",
    "ElementType",
    "ElementSpacing",
    "ElementDataFile",
    "BinaryData",
    "BinaryDataByteOrderMSB",
    "ElementByteOrderMSB",
    "CompressedData",
    "HeaderSize",
];

/// The format of a file named `name` (lower case) that begins with `head`
/// (its first [`SNIFF_BYTES`] or fewer), if it is one recognised here.
pub fn sniff(name: &str, head: &[u8]) -> Option<VolumeFormat> {
    let head = &head[..head.len().min(SNIFF_BYTES)];
    if let Some(format) = signature(head) {
        return Some(format);
    }
    let raw_name = RAW_EXTENSIONS.iter().any(|e| name.ends_with(e));
    // Two bytes is a weak signature: a raw volume may begin with them.
    if (!raw_name && head.starts_with(&[0x1f, 0x8b])) || name.ends_with(".gz") {
        return Some(if name.ends_with(".nii.gz") {
            VolumeFormat::Nifti
        } else {
            VolumeFormat::Gzip
        });
    }
    EXTENSIONS
        .iter()
        .find(|(e, _)| name.ends_with(e))
        .map(|&(_, format)| format)
}

/// A signature that only a file of that format carries.
fn signature(head: &[u8]) -> Option<VolumeFormat> {
    let at = |offset: usize, magic: &[u8]| head.get(offset..offset + magic.len()) == Some(magic);
    let int_at =
        |offset: usize| -> Option<[u8; 4]> { head.get(offset..offset + 4)?.try_into().ok() };
    let size_is = |offset: usize, n: i32| {
        int_at(offset).is_some_and(|b| i32::from_le_bytes(b) == n || i32::from_be_bytes(b) == n)
    };
    if at(0, b"NRRD000") {
        return Some(VolumeFormat::Nrrd);
    }
    if size_is(0, 348) && (at(344, b"n+1\0") || at(344, b"ni1\0"))
        || size_is(0, 540) && (at(4, b"n+2\0") || at(4, b"ni2\0"))
    {
        return Some(VolumeFormat::Nifti);
    }
    if at(128, b"DICM") {
        return Some(VolumeFormat::Dicom);
    }
    if at(0, b"# vtk DataFile") {
        return Some(VolumeFormat::VtkLegacy);
    }
    let text = String::from_utf8_lossy(head);
    let text = text.trim_start_matches('\u{feff}').trim_start();
    if (text.starts_with("<?xml") || text.starts_with("<VTKFile")) && text.contains("<VTKFile") {
        return Some(VolumeFormat::VtkXml);
    }
    let first_key = text
        .lines()
        .next()
        .and_then(|line| line.split_once('='))
        .map(|(key, _)| key.trim());
    if first_key.is_some_and(|key| META_IMAGE_KEYS.contains(&key)) {
        return Some(VolumeFormat::MetaImage);
    }
    None
}

/// The first bytes of a regular file.
fn head(path: &Path) -> std::io::Result<Vec<u8>> {
    let (file, _) = files::open_regular(path)?;
    let mut bytes = Vec::with_capacity(SNIFF_BYTES);
    file.take(SNIFF_BYTES as u64).read_to_end(&mut bytes)?;
    Ok(bytes)
}

/// Whether a folder holds DICOM slices (by name, a DICOMDIR, or content).
fn dicom_folder(path: &Path) -> bool {
    let Ok(entries) = std::fs::read_dir(path) else {
        return false;
    };
    entries.flatten().take(FOLDER_ENTRIES).any(|entry| {
        let name = entry.file_name().to_string_lossy().to_lowercase();
        name == "dicomdir"
            || name.ends_with(".dcm")
            || name.ends_with(".dicom")
            || entry.file_type().is_ok_and(|t| t.is_file())
                && head(&entry.path()).is_ok_and(|h| signature(&h) == Some(VolumeFormat::Dicom))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn nifti1(magic: &[u8; 4], big_endian: bool) -> Vec<u8> {
        let mut h = vec![0u8; 352];
        let size = if big_endian {
            348i32.to_be_bytes()
        } else {
            348i32.to_le_bytes()
        };
        h[..4].copy_from_slice(&size);
        h[344..348].copy_from_slice(magic);
        h
    }

    #[test]
    fn signatures_are_recognised_whatever_the_name() {
        let mut dicom = vec![0u8; 200];
        dicom[128..132].copy_from_slice(b"DICM");
        let mut nifti2 = vec![0u8; 540];
        nifti2[..4].copy_from_slice(&540i32.to_le_bytes());
        nifti2[4..8].copy_from_slice(b"n+2\0");
        let cases: Vec<(Vec<u8>, VolumeFormat)> = vec![
            (b"NRRD0004\ntype: short\n".to_vec(), VolumeFormat::Nrrd),
            (nifti1(b"n+1\0", false), VolumeFormat::Nifti),
            (nifti1(b"ni1\0", true), VolumeFormat::Nifti),
            (nifti2, VolumeFormat::Nifti),
            (dicom, VolumeFormat::Dicom),
            (
                b"# vtk DataFile Version 3.0\nhead\nBINARY\n".to_vec(),
                VolumeFormat::VtkLegacy,
            ),
            (
                b"<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\">".to_vec(),
                VolumeFormat::VtkXml,
            ),
            (
                b"<VTKFile type=\"ImageData\" version=\"1.0\">".to_vec(),
                VolumeFormat::VtkXml,
            ),
            (
                b"ObjectType = Image\nNDims = 3\n".to_vec(),
                VolumeFormat::MetaImage,
            ),
            (
                b"NDims = 3\r\nDimSize = 4 4 4\r\n".to_vec(),
                VolumeFormat::MetaImage,
            ),
        ];
        for (bytes, format) in cases {
            // Even named as raw: no raw volume begins with these.
            for name in ["scan", "scan.raw", "scan.dat"] {
                assert_eq!(sniff(name, &bytes), Some(format), "{name}: {bytes:?}");
            }
        }
    }

    #[test]
    fn names_tell_where_the_content_does_not() {
        let zeros = [0u8; 64];
        for (name, format) in [
            ("a.nrrd", VolumeFormat::Nrrd),
            ("a.nhdr", VolumeFormat::Nrrd),
            ("a.nii", VolumeFormat::Nifti),
            ("a.nii.gz", VolumeFormat::Nifti),
            ("a.mha", VolumeFormat::MetaImage),
            ("a.mhd", VolumeFormat::MetaImage),
            ("a.vtk", VolumeFormat::VtkLegacy),
            ("a.vti", VolumeFormat::VtkXml),
            ("a.dcm", VolumeFormat::Dicom),
            ("a.raw.gz", VolumeFormat::Gzip),
        ] {
            assert_eq!(sniff(name, &zeros), Some(format), "{name}");
            assert_eq!(sniff(name, &[]), Some(format), "{name}, empty");
        }
    }

    #[test]
    fn raw_volumes_are_not_taken_for_a_format() {
        for name in ["head.raw", "head", "head.dat", "volume.u16"] {
            assert_eq!(sniff(name, &[]), None, "{name}");
            assert_eq!(sniff(name, &[0u8; 512]), None, "{name}");
            let ramp: Vec<u8> = (0..=255).collect();
            assert_eq!(sniff(name, &ramp), None, "{name}");
        }
        // A first voxel that happens to be gzip's two bytes, in a file
        // named as raw: still raw. Without such a name it is gzip.
        let gz = [0x1f, 0x8b, 8, 0, 0, 0];
        assert_eq!(sniff("ct.raw", &gz), None);
        assert_eq!(sniff("ct", &gz), Some(VolumeFormat::Gzip));
        // The NIfTI size without its magic, and text that is not a header.
        assert_eq!(sniff("x.raw", &nifti1(b"abc\0", false)), None);
        assert_eq!(sniff("x.raw", b"Comment = hello\n"), None);
        assert_eq!(sniff("x.raw", b"<?xml version=\"1.0\"?><svg>"), None);
    }

    #[test]
    fn files_and_folders_on_disk_are_recognised_and_specials_never_opened() {
        let dir = std::env::temp_dir().join(format!("caveray_format_{}", std::process::id()));
        let series = dir.join("series");
        std::fs::create_dir_all(&series).unwrap();
        let mut slice = vec![0u8; 300];
        slice[128..132].copy_from_slice(b"DICM");
        // Slices are often named without an extension.
        std::fs::write(series.join("IM0001"), &slice).unwrap();
        assert_eq!(VolumeFormat::of(&series), Some(VolumeFormat::DicomSeries));
        let nrrd = dir.join("ct.raw");
        std::fs::write(&nrrd, b"NRRD0005\n").unwrap();
        assert_eq!(VolumeFormat::of(&nrrd), Some(VolumeFormat::Nrrd));
        let raw = dir.join("plain.raw");
        std::fs::write(&raw, [0u8; 1000]).unwrap();
        assert_eq!(VolumeFormat::of(&raw), None);
        let empty = dir.join("empty");
        std::fs::create_dir_all(&empty).unwrap();
        assert_eq!(VolumeFormat::of(&empty), None);
        assert_eq!(VolumeFormat::of(&dir.join("missing.nrrd")), None);
        let fifo = dir.join("fifo.nrrd");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        assert!(
            made.is_ok_and(|s| s.success()),
            "mkfifo (coreutils) is needed"
        );
        // Opening a FIFO would wait for a writer forever.
        assert_eq!(VolumeFormat::of(&fifo), None);
        assert_eq!(VolumeFormat::of(Path::new("/dev/zero")), None);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
