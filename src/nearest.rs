//! "Did you mean": the known name nearest a misspelt one, for every message that refuses a name
//! (a vector's key, a profile's flag).

/// The known name within a typo's reach of `name` (at most 2 edits, or a quarter of its
/// length), the nearest first found.
pub(crate) fn nearest<'a>(name: &str, known: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    known
        .into_iter()
        .map(|k| (distance(name, k), k))
        .filter(|(d, k)| *d <= 2.max(k.len() / 4))
        .min()
        .map(|(_, k)| k)
}

/// Levenshtein distance.
fn distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let cur = row[j + 1];
            row[j + 1] = (prev + usize::from(ca != *cb)).min(row[j] + 1).min(cur + 1);
            prev = cur;
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distance_counts_edits() {
        assert_eq!(distance("oprands", "operands"), 1);
        assert_eq!(distance("basis", "basis"), 0);
        assert_eq!(distance("", "abc"), 3);
    }

    #[test]
    fn only_a_likely_typo_is_suggested() {
        assert_eq!(nearest("SM07", ["SM701", "SM705"]), Some("SM701"));
        assert_eq!(nearest("M8004", ["SM701", "SM705"]), None);
    }
}
