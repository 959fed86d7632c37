//! Delta-transmission (Zheng 2007 §7.3, Fig. 7.4): of the PVS rows requested in one
//! prefetching transaction, only the objects the client does not already hold are
//! sent, ΔS = S_J − (S_J ∩ S_I), where S_J is the union of the requested rows and S_I
//! the union of the cached ones. The thesis computes it with AND and XOR over boolean
//! rows; over sorted id lists the same set is a merge and a filter.

use super::source::ObjectId;

/// ΔS: the union of the `requested` rows (each ascending) without the objects `held`,
/// ascending.
pub fn delta(requested: &[&[ObjectId]], held: impl Fn(ObjectId) -> bool) -> Vec<ObjectId> {
    let mut out: Vec<ObjectId> = requested
        .iter()
        .flat_map(|row| row.iter().copied())
        .filter(|&id| !held(id))
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fig_7_3() {
        // C1 holds 1, 2, 3, 4 and 8; its neighbour C2 sees 1 to 6.
        let held = [1, 2, 3, 4, 8];
        assert_eq!(
            delta(&[&[1, 2, 3, 4, 5, 6]], |id| held.contains(&id)),
            [5, 6]
        );
    }

    #[test]
    fn union_of_rows_less_what_is_held() {
        let held = [2, 7];
        let sent = delta(&[&[1, 2, 3], &[3, 4, 7], &[]], |id| held.contains(&id));
        assert_eq!(sent, [1, 3, 4]);
        assert!(delta(&[], |_| false).is_empty());
        assert!(delta(&[&[5, 6]], |_| true).is_empty());
    }
}
