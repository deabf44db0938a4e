//! `caveray render` as one rank of an MPI job (`mpirun -np N caveray
//! render ...`, built with the `mpi` feature): the walls shared out over
//! the ranks, a barrier after the frame (the swap lock), and every rank's
//! images and timings gathered on rank 0, which writes them. Alone, it is
//! rank 0 of 1.

use anari_library_caveray::cave::Eye;
use serde::{Deserialize, Serialize};

use crate::Failure;

pub struct Cluster {
    #[cfg(feature = "mpi")]
    world: Option<&'static anari_library_caveray::cluster::mpi::World>,
}

/// The job this process joined, ended by [`end`] when the command is done.
#[cfg(feature = "mpi")]
static JOINED: std::sync::OnceLock<anari_library_caveray::cluster::mpi::World> =
    std::sync::OnceLock::new();

/// Ends this process's part in the job it joined, if it joined one: MPI
/// finalised where the command succeeded, the whole job aborted where it
/// failed (the other ranks would wait for it forever).
pub fn end(succeeded: bool) {
    #[cfg(feature = "mpi")]
    if let Some(w) = JOINED.get() {
        w.end(succeeded);
    }
    #[cfg(not(feature = "mpi"))]
    let _ = succeeded;
}

impl Cluster {
    /// Joins the job that started this process, if one did.
    pub fn join() -> Result<Self, Failure> {
        let launched = anari_library_caveray::cluster::launched_size().filter(|&n| n > 1);
        #[cfg(feature = "mpi")]
        {
            let world = match (launched, JOINED.get()) {
                (None, _) => None,
                (Some(_), Some(w)) => Some(w),
                (Some(_), None) => {
                    let w = anari_library_caveray::cluster::mpi::World::join()
                        .map_err(Failure::Runtime)?;
                    Some(JOINED.get_or_init(|| w))
                }
            };
            Ok(Self { world })
        }
        #[cfg(not(feature = "mpi"))]
        {
            if let Some(n) = launched {
                eprintln!(
                    "caveray: started as one of {n} MPI processes, but built without the mpi feature: this process renders every view on its own (build with --features mpi)"
                );
            }
            Ok(Self {})
        }
    }

    pub fn rank(&self) -> usize {
        #[cfg(feature = "mpi")]
        if let Some(w) = &self.world {
            return w.rank();
        }
        0
    }

    pub fn size(&self) -> usize {
        #[cfg(feature = "mpi")]
        if let Some(w) = &self.world {
            return w.size();
        }
        1
    }

    pub fn is_root(&self) -> bool {
        self.rank() == 0
    }

    /// Waits for every rank: the swap lock's barrier.
    pub fn barrier(&self) -> Result<(), Failure> {
        #[cfg(feature = "mpi")]
        if let Some(w) = &self.world {
            return w.barrier().map_err(Failure::Runtime);
        }
        Ok(())
    }

    /// Every rank's share, on rank 0 in rank order (empty elsewhere).
    pub fn gather(&self, share: &Share) -> Result<Vec<Share>, Failure> {
        if self.size() == 1 {
            return Ok(vec![share.clone()]);
        }
        self.gather_bytes(&share.to_bytes()?)?
            .iter()
            .map(|b| Share::from_bytes(b))
            .collect()
    }

    /// Every rank's `bytes`, on rank 0 in rank order (empty elsewhere).
    pub fn gather_bytes(&self, bytes: &[u8]) -> Result<Vec<Vec<u8>>, Failure> {
        #[cfg(feature = "mpi")]
        if let Some(w) = &self.world {
            return w.gather(bytes).map_err(Failure::Runtime);
        }
        Ok(vec![bytes.to_vec()])
    }

    /// Sends `to[j]` to rank j; returns what each rank sent this one, in
    /// rank order (direct-send). Alone, its own message.
    pub fn exchange(&self, to: Vec<Vec<u8>>) -> Result<Vec<Vec<u8>>, Failure> {
        #[cfg(feature = "mpi")]
        if let Some(w) = &self.world {
            return w.exchange(&to).map_err(Failure::Runtime);
        }
        Ok(to)
    }

    /// Every rank's `value`, on every rank in rank order, as JSON over the
    /// wire.
    pub fn all_gather_json<T: Serialize + serde::de::DeserializeOwned>(
        &self,
        value: &T,
    ) -> Result<Vec<T>, Failure> {
        let json = |e: serde_json::Error| Failure::Runtime(format!("a rank's share: {e}"));
        let bytes = serde_json::to_vec(value).map_err(json)?;
        #[cfg(feature = "mpi")]
        if let Some(w) = &self.world {
            return w
                .all_gather(&bytes)
                .map_err(Failure::Runtime)?
                .iter()
                .map(|b| serde_json::from_slice(b).map_err(json))
                .collect();
        }
        Ok(vec![serde_json::from_slice(&bytes).map_err(json)?])
    }

    /// Every rank's `value`, on rank 0 in rank order (empty elsewhere),
    /// as JSON over the wire.
    pub fn gather_json<T: Serialize + serde::de::DeserializeOwned>(
        &self,
        value: &T,
    ) -> Result<Vec<T>, Failure> {
        let json = |e: serde_json::Error| Failure::Runtime(format!("a rank's share: {e}"));
        let bytes = serde_json::to_vec(value).map_err(json)?;
        self.gather_bytes(&bytes)?
            .iter()
            .map(|b| serde_json::from_slice(b).map_err(json))
            .collect()
    }
}

/// What one rank made of a frame: its walls' records (as JSON, with the
/// wall's index), their images, and its times.
#[derive(Clone, Serialize, Deserialize)]
pub struct Share {
    pub rank: usize,
    pub walls: Vec<String>,
    /// Rendering its views, upload included.
    pub render_ms: f64,
    /// Waiting at the barrier for the slowest rank.
    pub barrier_ms: f64,
    pub records: Vec<(usize, serde_json::Value)>,
    /// Wall index, eye name, width and height of each image, whose RGBA
    /// bytes follow the header in that order.
    pub images: Vec<(usize, String, u32, u32)>,
    #[serde(skip)]
    pub pixels: Vec<Vec<u8>>,
}

impl Share {
    /// A rank's share of a frame: its walls, its times (render, barrier),
    /// its records and its images.
    pub fn of(
        rank: usize,
        walls: Vec<String>,
        (render_ms, barrier_ms): (f64, f64),
        records: &[(usize, crate::render::ViewRecord)],
        images: &[(usize, Eye, image::RgbaImage)],
    ) -> Result<Self, Failure> {
        let records = records
            .iter()
            .map(|(i, r)| {
                serde_json::to_value(r)
                    .map(|v| (*i, v))
                    .map_err(|e| Failure::Runtime(e.to_string()))
            })
            .collect::<Result<_, _>>()?;
        Ok(Self {
            rank,
            walls,
            render_ms,
            barrier_ms,
            records,
            images: images
                .iter()
                .map(|(i, e, im)| (*i, e.name().to_string(), im.width(), im.height()))
                .collect(),
            pixels: images.iter().map(|(.., im)| im.as_raw().clone()).collect(),
        })
    }

    /// A JSON header (its length first, 8 bytes) and the images' bytes.
    fn to_bytes(&self) -> Result<Vec<u8>, Failure> {
        let head = serde_json::to_vec(self).map_err(|e| Failure::Runtime(e.to_string()))?;
        let mut out = (head.len() as u64).to_le_bytes().to_vec();
        out.extend(head);
        for p in &self.pixels {
            out.extend(p);
        }
        Ok(out)
    }

    fn from_bytes(bytes: &[u8]) -> Result<Self, Failure> {
        let bad = |why: &str| Failure::Runtime(format!("a rank's share is malformed: {why}"));
        let len = bytes
            .get(..8)
            .and_then(|b| b.try_into().ok())
            .map(u64::from_le_bytes)
            .ok_or_else(|| bad("no header length"))?;
        let end = usize::try_from(len)
            .ok()
            .and_then(|l| l.checked_add(8))
            .filter(|&e| e <= bytes.len())
            .ok_or_else(|| bad("the header runs past the end"))?;
        let mut share: Share =
            serde_json::from_slice(&bytes[8..end]).map_err(|e| bad(&e.to_string()))?;
        let mut at = end;
        for &(_, _, w, h) in &share.images {
            let n = 4 * w as usize * h as usize;
            let px = bytes
                .get(at..at + n)
                .ok_or_else(|| bad("short of pixels"))?;
            share.pixels.push(px.to_vec());
            at += n;
        }
        Ok(share)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_share_survives_its_bytes() {
        let share = Share {
            rank: 2,
            walls: vec!["front".into()],
            render_ms: 12.5,
            barrier_ms: 0.25,
            records: vec![(3, serde_json::json!({"wall": "front", "eye": "left"}))],
            images: vec![(3, "left".into(), 2, 1)],
            pixels: vec![vec![1, 2, 3, 4, 5, 6, 7, 8]],
        };
        let bytes = share
            .to_bytes()
            .unwrap_or_else(|_| panic!("a share encodes"));
        let back = Share::from_bytes(&bytes).unwrap_or_else(|_| panic!("and decodes"));
        assert_eq!(back.rank, 2);
        assert_eq!(back.records, share.records);
        assert_eq!(back.images, share.images);
        assert_eq!(back.pixels, share.pixels);
        assert!(Share::from_bytes(&[1, 0, 0]).is_err());
        let mut short = bytes;
        short.pop();
        assert!(Share::from_bytes(&short).is_err());
    }
}
