//! One journal entry as the store takes it.

use crate::edit::Edit;

/// An applied edit, the world revision it produced, and (for the change history a
/// restart reads back) the description of what it changed.
#[derive(Debug, Clone, Copy)]
pub struct Entry<'a> {
    /// The world's revision after the edit.
    pub revision: u64,
    /// The edit, as applied.
    pub edit: &'a Edit,
    /// What it changed, as the change feed describes it (JSON text), if kept.
    pub change: Option<&'a str>,
}

impl<'a> Entry<'a> {
    /// The entry of `edit`, which produced `revision`, with no change description.
    pub fn new(revision: u64, edit: &'a Edit) -> Self {
        Entry {
            revision,
            edit,
            change: None,
        }
    }

    /// The same entry with the description `change`.
    pub fn with_change(self, change: Option<&'a str>) -> Self {
        Entry { change, ..self }
    }
}
