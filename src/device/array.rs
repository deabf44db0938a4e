//! ANARI arrays: device-owned memory, or the host's memory shared until the
//! device no longer needs it.

use std::sync::Arc;

use super::object::{ObjectCell, ObjectRef};
use super::types::words;
use super::types::DataType;
use crate::scene::Lent;

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
    /// The host's memory, which the renderers read in place; `captured`:
    /// the host gave a deleter, and the memory stays valid until the
    /// device calls it (when the last reader drops the `Lent`).
    Host { lent: Arc<Lent>, captured: bool },
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
        let len = byte_len(element, dims).unwrap_or(0) as usize;
        let (ptr, captured) = (memory.ptr(), memory.captured());
        // SAFETY: the host promised `len` readable bytes at `ptr` until it
        // releases the array (shared) or the device calls its deleter
        // (captured: dropping `memory`, when the last reader is gone).
        let lent = unsafe { Lent::new(ptr, len, Box::new(memory)) };
        Self::new(element, dims, Storage::Host { lent, captured })
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
            Storage::Host { lent, .. } => lent.bytes().as_ptr().cast_mut(),
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
            Storage::Host { lent, .. } => &lent.bytes()[..len.min(lent.bytes().len())],
        }
    }

    /// The host's memory behind a shared array, for a renderer to read in
    /// place; `None` for a device-owned array.
    pub fn lent(&self) -> Option<&Arc<Lent>> {
        match &self.storage {
            Storage::Host { lent, .. } => Some(lent),
            Storage::Owned(_) => None,
        }
    }

    /// The host released a shared array nothing uses any more: scenes
    /// that a render may still be reading, and renderers' caches of past
    /// scenes, may hold its memory. Waits for those renders; the caches,
    /// which no later scene can reach without an object that uses the
    /// array, then read zeros, never the host's freed memory.
    pub fn retire(&self) {
        if let Some(Storage::Host {
            lent,
            captured: false,
        }) = Some(&self.storage)
        {
            if Arc::strong_count(lent) > 1 {
                lent.retire();
            }
        }
    }

    /// The elements as little helpers read them: FLOAT32 components.
    pub fn f32s(&self) -> Vec<f32> {
        words(self.bytes()).map(f32::from_ne_bytes).collect()
    }

    /// ANARI's array lifetime: a shared array's memory may be freed by the
    /// host right after it releases its last handle, so an array that is
    /// still used then copies its elements into memory of its own (after
    /// every render that may read the host's bytes has ended). Captured
    /// and device-owned arrays stay as they are. `Ok(true)` if a copy was
    /// made; `Err` if it could not be allocated, and then the array holds
    /// no elements, never the host's freed memory.
    pub fn privatize(&mut self) -> Result<bool, String> {
        let Storage::Host {
            lent,
            captured: false,
        } = &self.storage
        else {
            return Ok(false);
        };
        let copied = lent.privatize();
        if copied.is_err() {
            self.dims = [0, 1, 1];
        }
        copied.map_err(|e| format!("{e} ({})", self.element))
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
