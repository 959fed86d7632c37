//! A walk's frames as one CSV text, a header and a row a frame: what the reports that
//! keep their frames give back (those that hand them on write each row as it ends).

/// `header`, then `row` of each of `frames`, each line ended.
pub(crate) fn table<'a, F: 'a>(
    header: &str,
    frames: impl IntoIterator<Item = &'a F>,
    row: impl Fn(&F) -> String,
) -> String {
    let mut s = format!("{header}\n");
    for f in frames {
        s.push_str(&row(f));
        s.push('\n');
    }
    s
}
