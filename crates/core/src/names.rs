//! Names of the library's option enums, as the command line, glTF extras and manifests spell
//! them. [`named_enum!`] gives an enum its `ALL`, `NAMES`, `name`, `parse`, `FromStr` and
//! `Display` from one table, so each enum owns its spelling and its parse error lists the
//! names it knows (clap takes any `FromStr` type as an option value).

/// A name that is not one of an enum's.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown {what} '{got}' (known: {known})")]
pub struct UnknownName {
    /// What was being named ("attenuation", "tone operator", …).
    pub what: &'static str,
    pub got: String,
    /// The known names, comma-separated.
    pub known: String,
}

impl UnknownName {
    pub fn new(what: &'static str, got: &str, known: &[&str]) -> UnknownName {
        UnknownName {
            what,
            got: got.to_string(),
            known: known.join(", "),
        }
    }
}

/// Implement `ALL`, `NAMES`, `name()`, `parse()`, `FromStr` and `Display` for a unit-only enum:
/// `named_enum!(Type, "what it is", { Variant => "name", … } [, aliases { "other" => Variant }])`.
#[macro_export]
macro_rules! named_enum {
    ($ty:ident, $what:literal, { $($v:ident => $n:literal),+ $(,)? }
     $(, aliases { $($a:literal => $av:ident),* $(,)? })?) => {
        impl $ty {
            /// Every value, in the order of [`Self::NAMES`].
            pub const ALL: &'static [$ty] = &[$($ty::$v),+];
            /// The names `parse` accepts (besides aliases).
            pub const NAMES: &'static [&'static str] = &[$($n),+];
            /// This value's name.
            pub fn name(self) -> &'static str {
                match self {
                    $($ty::$v => $n),+
                }
            }
            /// The value of a name (or alias).
            pub fn parse(s: &str) -> Option<$ty> {
                match s {
                    $($n => Some($ty::$v),)+
                    $($($a => Some($ty::$av),)*)?
                    _ => None,
                }
            }
        }
        impl ::std::str::FromStr for $ty {
            type Err = $crate::names::UnknownName;
            fn from_str(s: &str) -> Result<Self, Self::Err> {
                $ty::parse(s).ok_or_else(|| $crate::names::UnknownName::new($what, s, $ty::NAMES))
            }
        }
        impl ::std::fmt::Display for $ty {
            fn fmt(&self, f: &mut ::std::fmt::Formatter<'_>) -> ::std::fmt::Result {
                f.write_str(self.name())
            }
        }
    };
}

#[cfg(test)]
mod tests {
    #[derive(Clone, Copy, Debug, PartialEq)]
    enum Colour {
        Red,
        DarkBlue,
    }
    crate::named_enum!(Colour, "colour", { Red => "red", DarkBlue => "dark-blue" },
        aliases { "navy" => DarkBlue });

    #[test]
    fn names_parse_and_print_both_ways() {
        for &c in Colour::ALL {
            assert_eq!(c.name().parse::<Colour>(), Ok(c));
            assert_eq!(c.to_string(), c.name());
        }
        assert_eq!("navy".parse::<Colour>(), Ok(Colour::DarkBlue));
        let e = "green".parse::<Colour>().unwrap_err();
        assert_eq!(
            e.to_string(),
            "unknown colour 'green' (known: red, dark-blue)"
        );
    }
}
