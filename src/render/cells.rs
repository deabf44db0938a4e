//! Time-budgeted rendering in cells (Buchacher's thesis, Algorithms 4 and
//! 5): an image is split into a grid of cells, and each display frame
//! renders as many of them as their predicted times allow before the warp
//! deadline. A cell's prediction is the largest time its neighbourhood
//! (itself and the eight around it) took in the last image, times a bias
//! of at least 1; the image is swapped in once every cell is done.

use glam::UVec2;

/// An image of `size` cut into `cells` (columns, rows) of nearly equal
/// size, numbered row by row from the lower left.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CellGrid {
    pub size: UVec2,
    pub cells: UVec2,
}

impl CellGrid {
    /// `cells` per axis, at most one per pixel.
    pub fn new(size: UVec2, cells: UVec2) -> Result<Self, String> {
        if size.min_element() == 0 {
            return Err(format!("an image of {}x{} has no cells", size.x, size.y));
        }
        if cells.min_element() == 0 {
            return Err(format!(
                "a cell grid needs at least 1x1 cells, got {}x{}",
                cells.x, cells.y
            ));
        }
        Ok(Self {
            size,
            cells: cells.min(size),
        })
    }

    pub fn count(&self) -> usize {
        (self.cells.x * self.cells.y) as usize
    }

    /// Lower-left pixel and size of cell `i`.
    pub fn rect(&self, i: usize) -> (UVec2, UVec2) {
        let c = UVec2::new(i as u32 % self.cells.x, i as u32 / self.cells.x);
        let edge = |k: u32, n: u32, len: u32| (u64::from(k) * u64::from(len) / u64::from(n)) as u32;
        let lo = UVec2::new(
            edge(c.x, self.cells.x, self.size.x),
            edge(c.y, self.cells.y, self.size.y),
        );
        let hi = UVec2::new(
            edge(c.x + 1, self.cells.x, self.size.x),
            edge(c.y + 1, self.cells.y, self.size.y),
        );
        (lo, hi - lo)
    }

    /// Cell `i` and its (up to eight) neighbours.
    pub fn neighbourhood(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        let (cx, cy) = (
            (i as u32 % self.cells.x) as i64,
            (i as u32 / self.cells.x) as i64,
        );
        let (w, h) = (i64::from(self.cells.x), i64::from(self.cells.y));
        (-1..=1)
            .flat_map(move |dy| (-1..=1).map(move |dx| (cx + dx, cy + dy)))
            .filter(move |&(x, y)| x >= 0 && y >= 0 && x < w && y < h)
            .map(move |(x, y)| (y * w + x) as usize)
    }
}

/// Predicts cell times from the last image's (Algorithm 5).
#[derive(Clone, Debug)]
pub struct Predictor {
    grid: CellGrid,
    bias: f64,
    /// Milliseconds each cell took in the last image it was rendered for.
    last: Vec<Option<f64>>,
}

impl Predictor {
    /// A predictor with no history; `bias` below 1 is raised to 1.
    pub fn new(grid: CellGrid, bias: f64) -> Self {
        Self {
            grid,
            bias: if bias.is_finite() { bias.max(1.0) } else { 1.0 },
            last: vec![None; grid.count()],
        }
    }

    /// The predicted milliseconds of cell `i`: bias times its
    /// neighbourhood's largest last time; with no history there, the
    /// largest of any cell; with none at all, 0 (render and learn).
    pub fn predict(&self, i: usize) -> f64 {
        let near = self
            .grid
            .neighbourhood(i)
            .filter_map(|k| self.last[k])
            .fold(None, |m: Option<f64>, t| Some(m.map_or(t, |m| m.max(t))));
        let any = || self.last.iter().flatten().copied().reduce(f64::max);
        self.bias * near.or_else(any).unwrap_or(0.0)
    }

    pub fn bias(&self) -> f64 {
        self.bias
    }

    pub fn record(&mut self, i: usize, ms: f64) {
        self.last[i] = Some(ms);
    }
}

/// One image in progress: which cell is next, and the predictions.
#[derive(Clone, Debug)]
pub struct CellRun {
    pub grid: CellGrid,
    pub predictor: Predictor,
    next: usize,
}

impl CellRun {
    pub fn new(grid: CellGrid, bias: f64) -> Self {
        Self {
            grid,
            predictor: Predictor::new(grid, bias),
            next: 0,
        }
    }

    /// The cell to render now with `left_ms` before the deadline, if its
    /// prediction fits (Algorithm 4). `first` says nothing has been
    /// rendered in this display frame yet: then one cell is rendered
    /// whatever its prediction, so an image too slow for any frame still
    /// progresses.
    pub fn next_cell(&self, left_ms: f64, first: bool) -> Option<usize> {
        let i = self.next;
        (i < self.grid.count() && (first || self.predictor.predict(i) <= left_ms)).then_some(i)
    }

    /// Cell `i` took `ms`.
    pub fn done(&mut self, i: usize, ms: f64) {
        self.predictor.record(i, ms);
        self.next = i + 1;
    }

    pub fn complete(&self) -> bool {
        self.next >= self.grid.count()
    }

    /// Starts the next image, keeping the predictions.
    pub fn restart(&mut self) {
        self.next = 0;
    }
}
