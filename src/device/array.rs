//! ANARI arrays: device-owned memory, or the host's memory shared until the
//! device no longer needs it.

use super::object::{ObjectCell, ObjectRef};
use super::types::words;
use super::types::DataType;

/// Memory the host lent to an array. Dropping it returns the memory to the
/// host (the C layer calls the host's deleter there, exactly once).
pub trait HostMemory: Send {
    fn ptr(&self) -> *const u8;
    /// Gives the memory back without releasing it (the array was never made).
    fn disown(&mut self);
    /// A captured array (the host gave a deleter): the memory stays valid
    /// until the device calls it. A shared one (no deleter) is the host's
    /// again once the host has released its last handle.
    fn captured(&self) -> bool;
}

enum Storage {
    /// u64 words keep every element type aligned.
    Owned(Vec<u64>),
    Host(Box<dyn HostMemory>),
}

pub struct Array {
    element: DataType,
    dims: [u64; 3],
    storage: Storage,
    pub(crate) mapped: bool,
    /// For arrays of objects: the objects, held while the array exists.
    pub(crate) objects: Vec<Option<ObjectRef>>,
}

impl Array {
    /// A zeroed device-owned array; `None` if it cannot be allocated.
    pub fn owned(element: DataType, dims: [u64; 3]) -> Option<Self> {
        let bytes = byte_len(element, dims)?;
        let words = usize::try_from(bytes.div_ceil(8)).ok()?;
        let mut v = Vec::new();
        v.try_reserve_exact(words).ok()?;
        v.resize(words, 0);
        Some(Self::new(element, dims, Storage::Owned(v)))
    }

    /// An array over the host's memory, which must hold
    /// `element.size() * dims.product()` bytes while the array exists.
    pub fn shared(element: DataType, dims: [u64; 3], memory: Box<dyn HostMemory>) -> Self {
        Self::new(element, dims, Storage::Host(memory))
    }

    fn new(element: DataType, dims: [u64; 3], storage: Storage) -> Self {
        Self {
            element,
            dims,
            storage,
            mapped: false,
            objects: Vec::new(),
        }
    }

    pub fn element(&self) -> DataType {
        self.element
    }
    pub fn dims(&self) -> [u64; 3] {
        self.dims
    }
    pub fn len(&self) -> u64 {
        self.dims.iter().product()
    }
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    pub(crate) fn ptr(&mut self) -> *mut u8 {
        match &mut self.storage {
            Storage::Owned(v) => v.as_mut_ptr().cast(),
            Storage::Host(m) => m.ptr().cast_mut(),
        }
    }

    /// The elements' bytes.
    pub fn bytes(&self) -> &[u8] {
        let len = byte_len(self.element, self.dims).unwrap_or(0) as usize;
        match &self.storage {
            Storage::Owned(v) => {
                // SAFETY: the words hold at least `len` initialised bytes.
                unsafe { std::slice::from_raw_parts(v.as_ptr().cast(), len) }
            }
            Storage::Host(m) if len == 0 || m.ptr().is_null() => &[],
            // SAFETY: the host promised `len` readable bytes while the array lives.
            Storage::Host(m) => unsafe { std::slice::from_raw_parts(m.ptr(), len) },
        }
    }

    /// The elements as little helpers read them: FLOAT32 components.
    pub fn f32s(&self) -> Vec<f32> {
        words(self.bytes()).map(f32::from_ne_bytes).collect()
    }

    /// ANARI's array lifetime: a shared array's memory may be freed by the
    /// host right after it releases its last handle, so an array that is
    /// still used then copies its elements into memory of its own. Captured
    /// and device-owned arrays stay as they are. `Ok(true)` if a copy was
    /// made; `Err` if it could not be allocated, and then the array holds
    /// no elements, never the host's freed memory.
    pub fn privatize(&mut self) -> Result<bool, String> {
        if !matches!(&self.storage, Storage::Host(m) if !m.captured()) {
            return Ok(false);
        }
        let len = byte_len(self.element, self.dims).unwrap_or(0);
        let copy = usize::try_from(len.div_ceil(8)).ok().and_then(|words| {
            let mut v: Vec<u64> = Vec::new();
            v.try_reserve_exact(words).ok()?;
            v.resize(words, 0);
            Some(v)
        });
        let Some(mut words) = copy else {
            self.storage = Storage::Owned(Vec::new());
            self.dims = [0, 1, 1];
            return Err(format!(
                "cannot copy {len} bytes of {} before the host frees them; the array is now empty",
                self.element
            ));
        };
        let bytes = self.bytes();
        // SAFETY: `words` has room for `len` bytes, and `bytes` is `len` long.
        unsafe {
            std::ptr::copy_nonoverlapping(bytes.as_ptr(), words.as_mut_ptr().cast(), bytes.len())
        };
        self.storage = Storage::Owned(words);
        Ok(true)
    }

    /// Handle values stored in an array of objects.
    pub(crate) fn handles(&self) -> Vec<u64> {
        words(self.bytes())
            .map(|w| usize::from_ne_bytes(w) as u64)
            .collect()
    }
}

/// Bytes of an array, or `None` when the count overflows.
pub fn byte_len(element: DataType, dims: [u64; 3]) -> Option<u64> {
    dims.iter()
        .try_fold(element.size() as u64, |acc, &d| acc.checked_mul(d))
        .filter(|&b| b <= isize::MAX as u64)
}

impl ObjectCell {
    /// `f` on the array, if the object is one.
    pub fn with_array<R>(&self, f: impl FnOnce(&mut Array) -> R) -> Option<R> {
        self.with_held(f)
    }
}
