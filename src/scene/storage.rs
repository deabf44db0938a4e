//! Where a grid's numbers live: in a vector of their own, or in a file
//! mapped read-only into memory, so that a file whose bytes are already
//! the numbers (raw, uncompressed NIfTI and MetaImage, raw NRRD, VTK's raw
//! appended data, in this machine's byte order) is never copied. Mapped pages are the page cache's: they cost no memory
//! until read, and the kernel may drop them again under pressure.
//!
//! A mapped file must not shrink while it is mapped: reading a page past
//! its new end raises SIGBUS. Only the command-line tool maps files; the
//! ANARI device renders hosts' arrays, which it copies.

use std::fmt;
use std::fs::File;
use std::marker::PhantomData;
use std::ops::Deref;
use std::os::fd::AsRawFd;
use std::sync::Arc;

/// A read-only map of a whole file.
pub struct Mapping {
    ptr: *mut libc::c_void,
    len: usize,
}

// SAFETY: the map is read-only and lives until the last owner drops it.
unsafe impl Send for Mapping {}
// SAFETY: as above; no one writes through it.
unsafe impl Sync for Mapping {}

impl Mapping {
    /// `file`'s first `len` bytes, mapped read-only and private.
    pub fn of(file: &File, len: usize) -> std::io::Result<Self> {
        if len == 0 {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "an empty file cannot be mapped",
            ));
        }
        // SAFETY: a fresh private read-only map of an open file; the
        // result is checked before use.
        let ptr = unsafe {
            libc::mmap(
                std::ptr::null_mut(),
                len,
                libc::PROT_READ,
                libc::MAP_PRIVATE,
                file.as_raw_fd(),
                0,
            )
        };
        if ptr == libc::MAP_FAILED {
            return Err(std::io::Error::last_os_error());
        }
        Ok(Self { ptr, len })
    }

    /// The whole file's bytes.
    pub fn bytes(&self) -> &[u8] {
        // SAFETY: `len` readable bytes from `ptr` while the map lives.
        unsafe { std::slice::from_raw_parts(self.ptr.cast::<u8>(), self.len) }
    }
}

impl Drop for Mapping {
    fn drop(&mut self) {
        // SAFETY: unmaps exactly the map `of` made, once.
        unsafe {
            libc::munmap(self.ptr, self.len);
        }
    }
}

/// Numbers of type `T`: owned, or `len` of them at `offset` bytes into a
/// mapped file. Reads as a slice either way.
pub enum Buf<T> {
    Owned(Vec<T>),
    Mapped {
        map: Arc<Mapping>,
        offset: usize,
        len: usize,
        kind: PhantomData<T>,
    },
}

impl<T: bytemuck::Pod> Buf<T> {
    /// `len` numbers at `offset` into `map`, where they lie within it and
    /// aligned for `T`; None otherwise.
    pub fn mapped(map: Arc<Mapping>, offset: usize, len: usize) -> Option<Self> {
        let bytes = len.checked_mul(std::mem::size_of::<T>())?;
        let end = offset.checked_add(bytes)?;
        let aligned = (map.ptr as usize + offset) % std::mem::align_of::<T>() == 0;
        (end <= map.len && aligned).then_some(Buf::Mapped {
            map,
            offset,
            len,
            kind: PhantomData,
        })
    }

    pub fn is_mapped(&self) -> bool {
        matches!(self, Buf::Mapped { .. })
    }
}

impl<T: bytemuck::Pod> Deref for Buf<T> {
    type Target = [T];
    fn deref(&self) -> &[T] {
        match self {
            Buf::Owned(v) => v,
            Buf::Mapped {
                map, offset, len, ..
            } => {
                let bytes = &map.bytes()[*offset..*offset + *len * std::mem::size_of::<T>()];
                bytemuck::cast_slice(bytes)
            }
        }
    }
}

impl<T> From<Vec<T>> for Buf<T> {
    fn from(v: Vec<T>) -> Self {
        Buf::Owned(v)
    }
}

impl<T: Clone> Clone for Buf<T> {
    fn clone(&self) -> Self {
        match self {
            Buf::Owned(v) => Buf::Owned(v.clone()),
            Buf::Mapped {
                map, offset, len, ..
            } => Buf::Mapped {
                map: Arc::clone(map),
                offset: *offset,
                len: *len,
                kind: PhantomData,
            },
        }
    }
}

impl<T: bytemuck::Pod + PartialEq> PartialEq for Buf<T> {
    fn eq(&self, other: &Self) -> bool {
        **self == **other
    }
}

impl<T: bytemuck::Pod + fmt::Debug> fmt::Debug for Buf<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let how = if self.is_mapped() { "mapped" } else { "owned" };
        write!(f, "{how} {} numbers", self.len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    #[test]
    fn a_mapped_file_reads_as_its_numbers() {
        let path = std::env::temp_dir().join(format!("caveray_map_{}", std::process::id()));
        let numbers: Vec<u16> = (0..1000).map(|i| i * 7).collect();
        let mut bytes = vec![0u8; 6];
        bytes.extend(numbers.iter().flat_map(|n| n.to_le_bytes()));
        std::fs::File::create(&path)
            .unwrap()
            .write_all(&bytes)
            .unwrap();
        let file = File::open(&path).unwrap();
        let map = Arc::new(Mapping::of(&file, bytes.len()).unwrap());
        std::fs::remove_file(&path).unwrap();
        let buf = Buf::<u16>::mapped(Arc::clone(&map), 6, 1000).unwrap();
        assert!(buf.is_mapped());
        assert_eq!(&*buf, &numbers[..]);
        assert_eq!(buf.clone(), Buf::from(numbers));
        // Past the end, or misaligned for the type: not mapped.
        assert!(Buf::<u16>::mapped(Arc::clone(&map), 6, 1001).is_none());
        assert!(Buf::<u16>::mapped(Arc::clone(&map), 5, 10).is_none());
        assert!(Buf::<u16>::mapped(map, usize::MAX, 1).is_none());
        assert!(Mapping::of(&file, 0).is_err());
    }
}
