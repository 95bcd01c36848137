//! The value parser of the flags that take one value of a library enum (`--format`,
//! `--method`, `--criterion`, `--ekf`, …). The libraries know nothing of clap: each such
//! enum has `ALL` (its values in the listed order), `name` (its one spelling, also its
//! `Display`, so `default_value_t` shows it) and `FromStr`. [`choice`] makes those the
//! flag's possible values, with clap's usual error for any other value (the list of
//! values, a close one suggested).

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use clap::{Arg, Command};
use std::ffi::OsStr;

/// A [`TypedValueParser`] accepting the names of a library enum's values (and aliases).
#[derive(Clone)]
pub struct Choice<T: 'static> {
    values: Vec<(PossibleValue, T)>,
}

/// The parser of a flag whose values are `all`, spelled by `name` (e.g.
/// `choice(&SweepFormat::ALL, SweepFormat::name)`).
pub fn choice<T: Copy + Send + Sync + 'static>(
    all: &[T],
    name: fn(&T) -> &'static str,
) -> Choice<T> {
    Choice {
        values: all
            .iter()
            .map(|v| (PossibleValue::new(name(v)), *v))
            .collect(),
    }
}

impl<T> Choice<T> {
    /// Accept `alias` for `value` too (not listed: an older spelling).
    pub fn alias(mut self, value: &'static str, alias: &'static str) -> Self {
        let (pv, _) = self
            .values
            .iter_mut()
            .find(|(pv, _)| pv.get_name() == value)
            .expect("an alias of a listed value");
        *pv = pv.clone().alias(alias);
        self
    }
}

impl<T: Copy + Send + Sync + 'static> TypedValueParser for Choice<T> {
    type Value = T;

    fn parse_ref(&self, cmd: &Command, arg: Option<&Arg>, value: &OsStr) -> Result<T, clap::Error> {
        // clap's own check and error message (as for a `ValueEnum`), then the value named
        let names = PossibleValuesParser::new(self.values.iter().map(|(pv, _)| pv.clone()));
        let s = names.parse_ref(cmd, arg, value)?;
        let ignore_case = arg.is_some_and(Arg::is_ignore_case_set);
        Ok(self
            .values
            .iter()
            .find(|(pv, _)| pv.matches(&s, ignore_case))
            .expect("the parser accepted a listed name")
            .1)
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        Some(Box::new(self.values.iter().map(|(pv, _)| pv.clone())))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pradar::mapping::grid::SilentBound;

    #[test]
    fn names_and_aliases_parse_and_others_are_refused() {
        let p = choice(&SilentBound::ALL, SilentBound::name).alias("leak", "true");
        let cmd = Command::new("t");
        let parse = |s: &str| p.parse_ref(&cmd, None, OsStr::new(s));
        for b in SilentBound::ALL {
            assert_eq!(parse(&b.to_string()).unwrap(), b);
        }
        assert_eq!(parse("true").unwrap(), SilentBound::Leak);
        assert!(parse("Leak").is_err() && parse("x").is_err());
        let listed: Vec<String> = p
            .possible_values()
            .unwrap()
            .map(|v| v.get_name().to_string())
            .collect();
        assert_eq!(listed, ["off", "leak", "nearer"]);
    }
}
