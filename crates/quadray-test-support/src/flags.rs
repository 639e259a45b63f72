//! The round trip a settings type's flags must make: a valid value, spelled as flags by its
//! `to_args`, parses back through a command's clap arguments to the value it was.

use clap::{Args, Command, FromArgMatches};
use proptest::strategy::Strategy;
use proptest::test_runner::{TestCaseError, TestRunner};
use std::fmt::{Debug, Display};

/// Checks with proptest that every value `settings` draws is valid (`validate`) and parses back
/// unchanged from `command` followed by its flags (`to_args`) through the command's arguments `A`,
/// out of which `settings_of` takes the settings. `command` is the command's name and the flags it
/// requires besides the settings (clap reads the first word as the program name). Panics naming the smallest value that fails and its flags.
pub fn assert_settings_round_trip<A, S, E>(
    command: &[&str],
    settings: impl Strategy<Value = S>,
    validate: impl Fn(&S) -> Result<(), E>,
    to_args: impl Fn(&S) -> Vec<String>,
    settings_of: impl Fn(A) -> S,
) where
    A: Args + FromArgMatches,
    S: Debug + PartialEq,
    E: Display,
{
    let parser = A::augment_args(Command::new("quadray"));
    let outcome = TestRunner::default().run(&settings, |value| {
        validate(&value).map_err(|e| TestCaseError::fail(format!("{value:?}: {e}")))?;
        let argv: Vec<String> = command
            .iter()
            .map(|word| word.to_string())
            .chain(to_args(&value))
            .collect();
        let fail = |e: clap::Error| TestCaseError::fail(format!("{argv:?}: {e}"));
        let matches = parser.clone().try_get_matches_from(&argv).map_err(fail)?;
        let parsed = settings_of(A::from_arg_matches(&matches).map_err(fail)?);
        if parsed != value {
            return Err(TestCaseError::fail(format!(
                "{argv:?} parses to {parsed:?}, not {value:?}"
            )));
        }
        Ok(())
    });
    if let Err(e) = outcome {
        panic!("{e}");
    }
}
