//! Where a grid's numbers live: in a vector of their own, or in a file
//! mapped read-only into memory, so that a file whose bytes are already
//! the numbers (raw, uncompressed NIfTI and MetaImage, raw NRRD, VTK's raw
//! appended data, in this machine's byte order) is never copied. Mapped pages are the page cache's: they cost no memory
//! until read, and the kernel may drop them again under pressure.
//!
//! A mapped file must not shrink while it is mapped: reading a page past
//! its new end raises SIGBUS. Only the command-line tool maps files.
//!
//! The ANARI device reads a host's shared arrays where they lie ([`Lent`]):
//! the host's memory until it releases the array, then a copy, made once,
//! after every render that may still read the host's bytes has ended.

use std::fmt;
use std::fs::File;
use std::marker::PhantomData;
use std::ops::Deref;
use std::os::fd::AsRawFd;
use std::sync::atomic::{AtomicPtr, Ordering};
use std::sync::{Arc, Condvar, Mutex, OnceLock};

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

    /// `len` bytes of zeros, mapped read-only: no memory until read.
    fn zeros(len: usize) -> std::io::Result<Self> {
        // SAFETY: a fresh private anonymous read-only map; the result is
        // checked before use.
        let ptr = unsafe {
            libc::mmap(
                std::ptr::null_mut(),
                len,
                libc::PROT_READ,
                libc::MAP_PRIVATE | libc::MAP_ANONYMOUS | libc::MAP_NORESERVE,
                -1,
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

/// Bytes a host lent: read where they lie while the host holds them; once
/// it takes them back ([`Lent::privatize`]), read from a copy. A render
/// registers as a reader ([`Lent::reading`]) for as long as it runs, so
/// the copy's switch waits for every render that may still read the
/// host's bytes, and no longer.
pub struct Lent {
    /// Where the bytes are now: the host's, or the copy's.
    ptr: AtomicPtr<u8>,
    len: usize,
    /// The copy, once made (words keep every element type aligned).
    copy: OnceLock<Box<[u64]>>,
    /// Readers by generation (the switch to the copy starts a new one)
    /// and the current generation.
    readers: Mutex<(usize, [usize; 2])>,
    left: Condvar,
    /// Keeps the host's memory (dropping it may return the memory to the
    /// host): until the copy is made, or until the last reader is gone.
    keeper: Mutex<Option<Box<dyn Send>>>,
}

impl Lent {
    /// `len` bytes at `ptr`, kept readable by `keeper` until it is
    /// dropped or the bytes are privatized.
    ///
    /// # Safety
    /// `ptr` must point to `len` readable bytes that nothing writes while
    /// `keeper` lives and [`Lent::privatize`] has not returned.
    pub unsafe fn new(ptr: *const u8, len: usize, keeper: Box<dyn Send>) -> Arc<Lent> {
        Arc::new(Lent {
            ptr: AtomicPtr::new(ptr.cast_mut()),
            len,
            copy: OnceLock::new(),
            readers: Mutex::new((0, [0; 2])),
            left: Condvar::new(),
            keeper: Mutex::new(Some(keeper)),
        })
    }

    /// The bytes, where they are now.
    #[inline(always)]
    pub fn bytes(&self) -> &[u8] {
        let ptr = self.ptr.load(Ordering::SeqCst);
        if self.len == 0 || ptr.is_null() {
            return &[];
        }
        // SAFETY: the host's bytes stay readable while a reader (or the
        // host's API thread, which privatizes) reads them; the copy lives
        // as long as `self`.
        unsafe { std::slice::from_raw_parts(ptr, self.len) }
    }

    /// Whether the bytes are a copy of the host's.
    pub fn is_copied(&self) -> bool {
        self.copy.get().is_some()
    }

    /// Registers a reader until the returned guard drops.
    pub fn reading(self: &Arc<Self>) -> Reading {
        let mut r = self.readers.lock().unwrap_or_else(|e| e.into_inner());
        let generation = r.0;
        r.1[generation % 2] += 1;
        Reading {
            lent: Arc::clone(self),
            generation,
        }
    }

    /// The host takes its bytes back: copies them, makes the copy what
    /// every later read sees, waits for the readers that may still read
    /// the host's bytes, then lets the host's memory go. `Ok(true)` if a
    /// copy was made; `Err` if it could not be allocated (the bytes then
    /// read as zeros, never as the host's freed memory).
    pub fn privatize(&self) -> Result<bool, String> {
        if self.is_copied() {
            return Ok(false);
        }
        let words = self.len.div_ceil(8);
        let mut copy: Vec<u64> = Vec::new();
        let made = copy.try_reserve_exact(words).is_ok();
        copy.resize(if made { words } else { 0 }, 0);
        let result = if made {
            // SAFETY: `copy` has room for `len` bytes; the host's bytes
            // are still readable (the host has not yet been told it may
            // free them).
            unsafe {
                std::ptr::copy_nonoverlapping(
                    self.bytes().as_ptr(),
                    copy.as_mut_ptr().cast::<u8>(),
                    self.len,
                )
            };
            Ok(true)
        } else {
            Err(format!(
                "cannot copy {} bytes before the host frees them; they read as zeros",
                self.len
            ))
        };
        let copy = self.copy.get_or_init(|| copy.into_boxed_slice());
        let new = if made {
            copy.as_ptr().cast::<u8>().cast_mut()
        } else {
            std::ptr::null_mut()
        };
        self.switch(new);
        result
    }

    /// The host takes its bytes back and nothing will render them again
    /// (only renderers' caches of past scenes still hold them): no copy;
    /// they read as zeros once the readers that may still read the
    /// host's bytes are done.
    pub fn retire(&self) {
        if !self.is_copied() {
            self.switch(std::ptr::null_mut());
        }
    }

    /// Makes `ptr` what every later read sees, waits for the readers that
    /// may still read the host's bytes, then lets the host's memory go.
    fn switch(&self, ptr: *mut u8) {
        self.ptr.store(ptr, Ordering::SeqCst);
        let mut r = self.readers.lock().unwrap_or_else(|e| e.into_inner());
        let old = r.0;
        r.0 += 1;
        while r.1[old % 2] > 0 {
            r = self.left.wait(r).unwrap_or_else(|e| e.into_inner());
        }
        drop(r);
        drop(self.keeper.lock().unwrap_or_else(|e| e.into_inner()).take());
    }
}

impl fmt::Debug for Lent {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let how = if self.is_copied() {
            "copied"
        } else {
            "the host's"
        };
        write!(f, "{} bytes, {how}", self.len)
    }
}

/// A render reading lent bytes: the host's stay valid until it drops.
pub struct Reading {
    lent: Arc<Lent>,
    generation: usize,
}

impl Drop for Reading {
    fn drop(&mut self) {
        let mut r = self.lent.readers.lock().unwrap_or_else(|e| e.into_inner());
        r.1[self.generation % 2] -= 1;
        drop(r);
        self.lent.left.notify_all();
    }
}

/// Numbers of type `T`: owned, `len` of them at `offset` bytes into a
/// mapped file, or into bytes a host lent. Reads as a slice each way.
pub enum Buf<T> {
    Owned(Vec<T>),
    Mapped {
        map: Arc<Mapping>,
        offset: usize,
        len: usize,
        kind: PhantomData<T>,
    },
    Lent {
        lent: Arc<Lent>,
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
        let aligned = (map.ptr as usize + offset).is_multiple_of(std::mem::align_of::<T>());
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

    /// The first `len` numbers of `lent`, where it holds them and its
    /// bytes (and any copy of them) are aligned for `T`; None otherwise.
    pub fn lent(lent: Arc<Lent>, len: usize) -> Option<Self> {
        let bytes = len.checked_mul(std::mem::size_of::<T>())?;
        let aligned = (lent.bytes().as_ptr() as usize).is_multiple_of(std::mem::align_of::<T>())
            && std::mem::align_of::<T>() <= std::mem::align_of::<u64>();
        (bytes <= lent.len && aligned).then_some(Buf::Lent {
            lent,
            len,
            kind: PhantomData,
        })
    }

    /// Bytes of memory it owns (allocated, not only used): none for
    /// numbers read where they lie, a host's copied once it took them
    /// back.
    pub fn heap_bytes(&self) -> u64 {
        match self {
            Buf::Owned(v) => (v.capacity() * std::mem::size_of::<T>()) as u64,
            Buf::Lent { lent, len, .. } if lent.is_copied() => {
                (len * std::mem::size_of::<T>()) as u64
            }
            Buf::Lent { .. } | Buf::Mapped { .. } => 0,
        }
    }

    /// The host's bytes these are read from, if they are.
    pub fn lender(&self) -> Option<&Arc<Lent>> {
        match self {
            Buf::Lent { lent, .. } => Some(lent),
            _ => None,
        }
    }
}

impl<T: bytemuck::Pod> Deref for Buf<T> {
    type Target = [T];
    // Inlined: traversals read vertices through it.
    #[inline(always)]
    fn deref(&self) -> &[T] {
        match self {
            Buf::Owned(v) => v,
            Buf::Mapped {
                map, offset, len, ..
            } => {
                let bytes = &map.bytes()[*offset..*offset + *len * std::mem::size_of::<T>()];
                bytemuck::cast_slice(bytes)
            }
            Buf::Lent { lent, len, .. } => {
                let bytes = lent.bytes();
                if bytes.is_empty() {
                    // A copy that could not be made: zeros, as many.
                    return zeros(*len);
                }
                bytemuck::cast_slice(&bytes[..*len * std::mem::size_of::<T>()])
            }
        }
    }
}

/// `len` zero numbers without allocating them: a lent buffer whose copy
/// failed reads as zeros (one shared page-backed map, grown as needed).
#[cold]
fn zeros<T: bytemuck::Pod>(len: usize) -> &'static [T] {
    static ZEROS: OnceLock<Option<Mapping>> = OnceLock::new();
    // 16 GiB of address space, no memory until read (and then the zero
    // page): larger than any one array a host can lend here.
    const SPAN: usize = 1 << 34;
    let map = ZEROS.get_or_init(|| Mapping::zeros(SPAN).ok());
    match map {
        Some(m) if len.saturating_mul(std::mem::size_of::<T>()) <= SPAN => {
            bytemuck::cast_slice(&m.bytes()[..len * std::mem::size_of::<T>()])
        }
        _ => &[],
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
            Buf::Lent { lent, len, .. } => Buf::Lent {
                lent: Arc::clone(lent),
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
        let how = match self {
            Buf::Owned(_) => "owned",
            Buf::Mapped { .. } => "mapped",
            Buf::Lent { .. } => "lent",
        };
        write!(f, "{how} {} numbers", self.len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    /// Lent bytes are read in place; privatizing copies them, after the
    /// readers of the host's bytes are done, and then lets the host's
    /// memory go; retiring reads zeros without a copy.
    #[test]
    fn lent_bytes_are_read_in_place_until_the_host_takes_them_back() {
        use std::sync::atomic::AtomicBool;
        struct Keeper(Arc<AtomicBool>);
        impl Drop for Keeper {
            fn drop(&mut self) {
                self.0.store(true, Ordering::SeqCst);
            }
        }
        let host: Vec<f32> = (0..1000).map(|i| i as f32).collect();
        let gone = Arc::new(AtomicBool::new(false));
        let bytes: &[u8] = bytemuck::cast_slice(&host);
        // SAFETY: `host` outlives every read below and is not written.
        let lent =
            unsafe { Lent::new(bytes.as_ptr(), bytes.len(), Box::new(Keeper(gone.clone()))) };
        let buf = Buf::<f32>::lent(Arc::clone(&lent), 1000).unwrap();
        assert_eq!(buf.as_ptr(), host.as_ptr(), "read in place");
        assert!(Buf::<f32>::lent(Arc::clone(&lent), 1001).is_none());
        // A reader holds the host's bytes: the switch waits for it.
        let reading = lent.reading();
        let switched = Arc::new(AtomicBool::new(false));
        let worker = {
            let (lent, switched) = (Arc::clone(&lent), Arc::clone(&switched));
            std::thread::spawn(move || {
                let copied = lent.privatize();
                switched.store(true, Ordering::SeqCst);
                copied
            })
        };
        std::thread::sleep(std::time::Duration::from_millis(100));
        assert!(!switched.load(Ordering::SeqCst), "privatize did not wait");
        assert!(!gone.load(Ordering::SeqCst));
        drop(reading);
        assert_eq!(worker.join().unwrap(), Ok(true));
        assert!(gone.load(Ordering::SeqCst), "the host's memory is kept");
        assert_ne!(buf.as_ptr(), host.as_ptr(), "still the host's bytes");
        assert_eq!(&*buf, &host[..]);
        // A reader registered after the switch does not hold it up again.
        let later = lent.reading();
        assert_eq!(lent.privatize(), Ok(false));
        drop(later);

        let gone = Arc::new(AtomicBool::new(false));
        // SAFETY: as above.
        let lent =
            unsafe { Lent::new(bytes.as_ptr(), bytes.len(), Box::new(Keeper(gone.clone()))) };
        let buf = Buf::<f32>::lent(Arc::clone(&lent), 1000).unwrap();
        lent.retire();
        assert!(gone.load(Ordering::SeqCst));
        assert_eq!(buf.len(), 1000);
        assert!(
            buf.iter().all(|&v| v == 0.0),
            "a retired buffer reads zeros"
        );
    }

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
