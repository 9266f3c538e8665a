//! A student's own equations as the settings carry them: the text of each quantity of the
//! equation sandbox ([`crate::teaching::sandbox`]) that replaces the lab's, none for the lab's own.
//!
//! Only text is held here (the settings come before the sandbox on the ladder):
//! [`crate::teaching::sandbox::carried`] compiles it, and refuses a text that does not compile when a
//! file is read.

use serde::{Deserialize, Serialize};

/// Each quantity's text, by the name the lab gives it: `d`, `shadowStart`, `shadowed`, `D`,
/// `R`. A text is the statements that compute its quantity (`let` lines and `NAME = …`);
/// absent, the quantity is the lab's. Only the texts given are written.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct EquationTexts {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub d: Option<String>,
    #[serde(rename = "shadowStart", skip_serializing_if = "Option::is_none")]
    pub shadow_start: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shadowed: Option<String>,
    #[serde(rename = "D", skip_serializing_if = "Option::is_none")]
    pub direct: Option<String>,
    #[serde(rename = "R", skip_serializing_if = "Option::is_none")]
    pub value: Option<String>,
}

impl EquationTexts {
    /// The quantities' names, in the order they are computed (the sandbox's `Quantity::ALL`).
    pub const NAMES: [&'static str; 5] = ["d", "shadowStart", "shadowed", "D", "R"];

    /// No text: the lab's own quantities.
    pub fn is_empty(&self) -> bool {
        self.texts().iter().all(|(_, t)| t.is_none())
    }

    /// Each quantity's name and text, in [`EquationTexts::NAMES`]' order.
    pub fn texts(&self) -> [(&'static str, Option<&str>); 5] {
        let names = Self::NAMES;
        [
            (names[0], self.d.as_deref()),
            (names[1], self.shadow_start.as_deref()),
            (names[2], self.shadowed.as_deref()),
            (names[3], self.direct.as_deref()),
            (names[4], self.value.as_deref()),
        ]
    }

    /// The text of the quantity named `name` (one of [`EquationTexts::NAMES`]).
    pub fn text_mut(&mut self, name: &str) -> Option<&mut Option<String>> {
        Some(match name {
            "d" => &mut self.d,
            "shadowStart" => &mut self.shadow_start,
            "shadowed" => &mut self.shadowed,
            "D" => &mut self.direct,
            "R" => &mut self.value,
            _ => return None,
        })
    }
}
