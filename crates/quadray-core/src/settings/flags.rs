//! The command-line flags that spell a settings value, derived from the settings' own clap
//! arguments and serde fields: a new setting needs no line here, and none in its technique's
//! `to_args`.

use clap::{ArgAction, Args, Command, FromArgMatches};
use serde::Serialize;
use serde_json::{Map, Value};

/// The flags that parse back to `settings` through `S`'s clap arguments, in their declared order:
/// `--name value`, a bare `--name` for a switch that is on. Each argument's value is the serde
/// field of the same name (clap's flattened groups are serde's nested structs); `spelled` gives
/// the text of those whose serde value is not the flag's (a size serde flattens, a field it
/// skips, an enum with data), by argument id. A `None` is left out, its default left to its rule,
/// and so is a switch at its default.
///
/// Panics naming the flag where neither serde nor `spelled` gives its text: a settings type that
/// needs a `spelled` entry, which its round-trip test finds.
pub fn to_args<S: Args + Serialize>(settings: &S, spelled: &[(&str, String)]) -> Vec<String> {
    // Through JSON text rather than `serde_json::to_value`: the text writes an f32 in its own
    // shortest digits (0.1), the value would widen it to f64 first (0.10000000149011612).
    let text = serde_json::to_string(settings).expect("settings serialise");
    let fields: Value = serde_json::from_str(&text).expect("serde_json reads its own text");
    let command = S::augment_args(Command::new("settings"));
    let ids: Vec<&str> = command
        .get_arguments()
        .map(|a| a.get_id().as_str())
        .collect();
    let mut values = Map::new();
    leaves(&fields, &ids, &mut values);
    let mut words = Vec::new();
    for arg in command.get_arguments() {
        let id = arg.get_id().as_str();
        let flag = format!(
            "--{}",
            arg.get_long()
                .unwrap_or_else(|| panic!("argument `{id}` has no long flag"))
        );
        if let Some((_, text)) = spelled.iter().find(|(name, _)| *name == id) {
            words.extend([flag, text.clone()]);
            continue;
        }
        match (values.get(id), arg.get_action()) {
            (Some(Value::Null), _) => {}
            (Some(Value::Bool(on)), ArgAction::SetTrue) => words.extend(on.then_some(flag)),
            (Some(Value::Bool(on)), ArgAction::SetFalse) => words.extend((!on).then_some(flag)),
            (Some(Value::String(text)), _) => words.extend([flag, text.clone()]),
            (Some(Value::Number(n)), _) => {
                // a whole f32 as Rust writes it (`1`, not JSON's `1.0`)
                let text = n.to_string();
                let whole = text.strip_suffix(".0").unwrap_or(&text);
                words.extend([flag, whole.to_string()])
            }
            (Some(Value::Bool(on)), _) => words.extend([flag, on.to_string()]),
            (value, _) => {
                panic!("{flag}: serde writes {value:?}, not the flag's text: spell it in `spelled`")
            }
        }
    }
    words
}

/// The serde fields of `value` by name, descending into the nested structs that are no argument
/// of their own (clap's flattened groups).
fn leaves(value: &Value, ids: &[&str], out: &mut Map<String, Value>) {
    let Value::Object(fields) = value else {
        return;
    };
    for (name, value) in fields {
        if value.is_object() && !ids.contains(&name.as_str()) {
            leaves(value, ids, out);
        } else {
            out.insert(name.clone(), value.clone());
        }
    }
}

/// `S` parsed from `args` alone (no program name): what a command line that flattens `S` makes
/// of them.
pub fn from_args<S: Args + FromArgMatches>(args: &[String]) -> Result<S, clap::Error> {
    let command = S::augment_args(Command::new("settings").no_binary_name(true));
    S::from_arg_matches(&command.try_get_matches_from(args)?)
}

/// The flags of `S` that `args` leaves out or writes as `defaults` (the default settings'
/// flags) do: none for settings with every field off its default, `Some` and switched, which is
/// what a round-trip test needs to hold every field to its flag.
pub fn flags_at_default<S: Args>(args: &[String], defaults: &[String]) -> Vec<String> {
    // a flag's word and the value after it, if one follows (a negative number does; a flag not)
    let written = |words: &[String], flag: &str| {
        let at = words.iter().position(|w| w == flag)?;
        Some(words.get(at + 1).filter(|w| !w.starts_with("--")).cloned())
    };
    S::augment_args(Command::new("settings"))
        .get_arguments()
        .filter_map(|a| a.get_long())
        .map(|long| format!("--{long}"))
        .filter(|flag| {
            let value = written(args, flag);
            value.is_none() || value == written(defaults, flag)
        })
        .collect()
}

/// The check each settings type's tests make of its flags (`to_args`: its `Settings::to_args`):
/// `every`, a value with each field off its default, writes no flag at its default (`defaults`:
/// the default settings' flags), and `every` and each of `others` parse back from their flags to
/// themselves. Panics naming the flags where not.
pub fn assert_flags_round_trip<S>(
    every: S,
    others: impl IntoIterator<Item = S>,
    defaults: &[String],
    to_args: impl Fn(&S) -> Vec<String>,
) where
    S: Args + FromArgMatches + PartialEq + std::fmt::Debug,
{
    let args = to_args(&every);
    assert_eq!(
        flags_at_default::<S>(&args, defaults),
        Vec::<String>::new(),
        "{args:?}"
    );
    for s in std::iter::once(every).chain(others) {
        let args = to_args(&s);
        let parsed = from_args::<S>(&args).unwrap_or_else(|e| panic!("{args:?}: {e}"));
        assert_eq!(parsed, s, "{args:?}");
    }
}

/// `command` with its help written for a terminal, in it and every subcommand: settings are
/// documented once, in rustdoc, and clap shows those docs as help, so an intra-doc link
/// (``[`Self::SHADOW_CORNERS_ACROSS`]``, ``[`quadray::Kind::item`]``) reads as the name it
/// links to (`` `SHADOW_CORNERS_ACROSS` ``, `` `item` ``).
pub fn terminal_help(command: Command) -> Command {
    command
        .mut_args(|mut arg| {
            if let Some(help) = arg.get_help().map(|h| unlinked(&h.to_string())) {
                arg = arg.help(help);
            }
            if let Some(help) = arg.get_long_help().map(|h| unlinked(&h.to_string())) {
                arg = arg.long_help(help);
            }
            arg
        })
        .mut_subcommands(terminal_help)
}

/// `text` with each intra-doc link ``[`a::b::Name`]`` as `` `Name` `` (a path of names only:
/// ``"`[` and `]`"`` is text).
fn unlinked(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(start) = rest.find("[`") {
        let path_and_rest = &rest[start + 2..];
        let path = path_and_rest
            .find("`]")
            .map(|end| &path_and_rest[..end])
            .filter(|p| {
                !p.is_empty()
                    && p.chars()
                        .all(|c| c.is_alphanumeric() || c == '_' || c == ':')
            });
        out.push_str(&rest[..start]);
        match path {
            Some(path) => {
                out.push('`');
                out.push_str(path.rsplit("::").next().unwrap_or(path));
                out.push('`');
                rest = &path_and_rest[path.len() + 2..];
            }
            None => {
                out.push_str("[`");
                rest = path_and_rest;
            }
        }
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::Size;

    /// A settings type with every kind of field: a number, a switch on and one off, an `Option`,
    /// a flag named otherwise than its field, a nested group and a value serde flattens.
    #[derive(Clone, Debug, PartialEq, Serialize, clap::Args)]
    struct Example {
        #[serde(flatten)]
        #[arg(long, default_value_t = Size::new(4, 4))]
        size: Size,
        #[arg(long = "scale", default_value_t = 0.1, allow_negative_numbers = true)]
        scale_factor: f32,
        #[arg(long, default_value_t = 1.0)]
        zoom: f32,
        #[arg(long)]
        level: Option<u32>,
        #[arg(long)]
        fast: bool,
        #[command(flatten)]
        group: Group,
    }

    #[derive(Clone, Debug, PartialEq, Serialize, clap::Args)]
    struct Group {
        #[arg(long, default_value = "left")]
        side: String,
        #[arg(long = "unweighted", action = ArgAction::SetFalse)]
        weighted: bool,
    }

    fn example() -> Example {
        Example {
            size: Size::new(3, 2),
            scale_factor: -0.3,
            zoom: 2.0,
            level: Some(7),
            fast: true,
            group: Group {
                side: "right".into(),
                weighted: false,
            },
        }
    }

    fn args(e: &Example) -> Vec<String> {
        to_args(e, &[("size", e.size.to_string())])
    }

    #[test]
    fn every_field_comes_back_and_is_written_once() {
        let e = example();
        let words = args(&e);
        assert_eq!(
            words.join(" "),
            "--size 3x2 --scale -0.3 --zoom 2 --level 7 --fast --side right --unweighted"
        );
        assert_eq!(from_args::<Example>(&words).unwrap(), e);
        let defaults = args(&from_args::<Example>(&[]).unwrap());
        assert!(flags_at_default::<Example>(&words, &defaults).is_empty());
        assert_eq!(flags_at_default::<Example>(&defaults, &defaults).len(), 7);
    }

    #[test]
    fn none_and_switches_at_their_default_stay_unwritten() {
        let e = Example {
            level: None,
            fast: false,
            group: Group {
                weighted: true,
                ..example().group
            },
            ..example()
        };
        let words = args(&e);
        assert_eq!(
            words.join(" "),
            "--size 3x2 --scale -0.3 --zoom 2 --side right"
        );
        assert_eq!(from_args::<Example>(&words).unwrap(), e);
        let defaults = args(&from_args::<Example>(&[]).unwrap());
        assert_eq!(
            flags_at_default::<Example>(&words, &defaults),
            ["--level", "--fast", "--unweighted"]
        );
    }

    #[test]
    #[should_panic(expected = "--size: serde writes None, not the flag's text")]
    fn a_field_serde_does_not_write_by_its_name_must_be_spelled() {
        to_args(&example(), &[]);
    }

    #[test]
    fn intra_doc_links_read_as_the_names_they_link() {
        assert_eq!(
            unlinked("over [`Self::ACROSS`], the [`quadray::Kind::item`] ones, [`Size`]"),
            "over `ACROSS`, the `item` ones, `Size`"
        );
        assert_eq!(unlinked("a [`dangling"), "a [`dangling");
        assert_eq!(unlinked("`[` and `]` step it"), "`[` and `]` step it");
        #[derive(clap::Parser)]
        struct Cli {
            /// Every [`Self::N`]-th.
            #[arg(long)]
            every: u32,
        }
        let mut command = terminal_help(<Cli as clap::CommandFactory>::command());
        let help = command.render_long_help().to_string();
        assert!(help.contains("Every `N`-th"), "{help}");
    }
}
