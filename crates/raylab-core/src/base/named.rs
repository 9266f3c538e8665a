//! Choices by name: the settings' enums (the stage, the view, the display transform, the
//! material and texture presets, the acceleration structure), each with its name on the
//! command line and in settings files, its label in the workbench's selectors, the list of
//! all of them, and parsing whose error lists the names. [`named_enum!`] writes all of that
//! from one table per enum.

use std::fmt::Display;

/// A choice among an enum's values, each with a name and a label ([`named_enum!`]).
pub trait NamedEnum: Copy + PartialEq + 'static {
    /// Every value, in the order the selectors list them.
    const ALL: &'static [Self];
    /// What a value is, for messages: `stage`, `view`, …
    const WHAT: &'static str;
    /// The name on the command line and in settings files.
    fn name(self) -> &'static str;
    /// The label in the workbench's selectors.
    fn label(self) -> &'static str;
}

/// The value of `T` named `s`, or the error that lists the names.
pub fn parse<T: NamedEnum>(s: &str) -> Result<T, String> {
    T::ALL
        .iter()
        .copied()
        .find(|v| v.name() == s)
        .ok_or_else(|| unknown(T::WHAT, s, T::ALL.iter().map(|v| v.name())))
}

/// The error for a name that is none of `names`: "unknown stage 'x' (expected flat, incoming,
/// direct, shadows, lab or path)".
pub fn unknown<N: Display>(what: &str, s: &str, names: impl IntoIterator<Item = N>) -> String {
    let names: Vec<String> = names.into_iter().map(|n| n.to_string()).collect();
    let expected = match names.split_last() {
        Some((last, [])) => last.clone(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
        None => String::new(),
    };
    format!("unknown {what} '{s}' (expected {expected})")
}

/// Names an enum of unit variants: `named_enum!(Type as "what" { Variant => "name", "Label";
/// … })`, the label optional (the name if left out). Makes the inherent `ALL` (every variant, in
/// the table's order), `name()` and `label()`, and the [`NamedEnum`], `Display` (the name) and
/// `FromStr` (by name; the error lists the names, [`unknown`]) impls. The `match`es it writes
/// are exhaustive, so a variant missing from the table does not compile.
macro_rules! named_enum {
    ($t:ident as $what:literal { $($v:ident => $name:literal $(, $label:literal)?;)+ }) => {
        impl $t {
            /// Every value, in the order the selectors list them.
            pub const ALL: [$t; [$(stringify!($v)),+].len()] = [$($t::$v),+];

            /// The name on the command line and in settings files.
            pub fn name(self) -> &'static str {
                match self {
                    $($t::$v => $name,)+
                }
            }

            /// The label in the workbench's selectors.
            pub fn label(self) -> &'static str {
                match self {
                    $($t::$v => $crate::base::named::named_enum!(@label $name $(, $label)?),)+
                }
            }
        }

        impl $crate::base::named::NamedEnum for $t {
            const ALL: &'static [Self] = &$t::ALL;
            const WHAT: &'static str = $what;

            fn name(self) -> &'static str {
                $t::name(self)
            }

            fn label(self) -> &'static str {
                $t::label(self)
            }
        }

        impl ::std::fmt::Display for $t {
            fn fmt(&self, f: &mut ::std::fmt::Formatter<'_>) -> ::std::fmt::Result {
                f.write_str(self.name())
            }
        }

        impl ::std::str::FromStr for $t {
            type Err = String;

            fn from_str(s: &str) -> Result<Self, Self::Err> {
                $crate::base::named::parse(s)
            }
        }
    };
    (@label $name:literal) => {
        $name
    };
    (@label $name:literal, $label:literal) => {
        $label
    };
}
pub(crate) use named_enum;

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Clone, Copy, Debug, PartialEq)]
    enum Three {
        A,
        B,
        C,
    }

    named_enum!(Three as "letter" {
        A => "a", "The first";
        B => "b";
        C => "c-c", "The third";
    });

    #[test]
    fn names_labels_and_messages() {
        assert_eq!(Three::ALL, [Three::A, Three::B, Three::C]);
        assert_eq!(Three::C.name(), "c-c");
        assert_eq!(Three::C.to_string(), "c-c");
        assert_eq!(Three::A.label(), "The first");
        assert_eq!(Three::B.label(), "b");
        assert_eq!("c-c".parse(), Ok(Three::C));
        assert_eq!(
            "d".parse::<Three>(),
            Err("unknown letter 'd' (expected a, b or c-c)".to_owned())
        );
        assert_eq!(unknown("x", "y", ["one"]), "unknown x 'y' (expected one)");
    }
}
