//! Which rank renders which walls.

/// `walls` walls (each with its eyes: a stereo pair stays on one rank, so
/// re-projection still applies) shared out over `ranks` ranks, round
/// robin: rank r gets walls r, r + ranks, ...; ranks past the walls get
/// none.
pub fn assign(walls: usize, ranks: usize) -> Vec<Vec<usize>> {
    let ranks = ranks.max(1);
    (0..ranks)
        .map(|r| (r..walls).step_by(ranks).collect())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_wall_goes_to_exactly_one_rank_and_loads_differ_by_at_most_one() {
        for walls in 0..12 {
            for ranks in 1..9 {
                let a = assign(walls, ranks);
                assert_eq!(a.len(), ranks);
                let mut all: Vec<usize> = a.iter().flatten().copied().collect();
                all.sort_unstable();
                assert_eq!(all, (0..walls).collect::<Vec<_>>());
                let most = a.iter().map(Vec::len).max().unwrap_or(0);
                let least = a.iter().map(Vec::len).min().unwrap_or(0);
                assert!(most - least <= 1, "{walls} walls over {ranks}: {a:?}");
            }
        }
        assert_eq!(assign(5, 4), vec![vec![0, 4], vec![1], vec![2], vec![3]]);
        assert_eq!(assign(3, 0), vec![vec![0, 1, 2]]);
    }
}
