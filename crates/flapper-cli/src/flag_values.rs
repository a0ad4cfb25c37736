//! Values of numeric flags. clap reads `-1` as a flag of its own unless an argument allows negative
//! numbers ("unexpected argument '-1' found", naming no flag), so every numeric flag allows them and
//! a negative count or seed is refused here instead, in clap's line naming the flag and the value:
//! `invalid value '-1' for '--episodes <EPISODES>': a count cannot be negative`.

use std::str::FromStr;

/// A count (episodes, iterations, environments, threads, ...): a whole number, 0 or more.
pub fn count(text: &str) -> Result<usize, String> {
    whole_number(text, "count")
}

/// A random seed: a whole number, 0 or more.
pub fn seed(text: &str) -> Result<u64, String> {
    whole_number(text, "seed")
}

fn whole_number<T: FromStr>(text: &str, what: &str) -> Result<T, String> {
    text.parse::<T>().map_err(|_| {
        if text.trim().parse::<i128>().is_ok_and(|number| number < 0) {
            format!("a {what} cannot be negative")
        } else {
            format!("a {what} is a whole number, 0 or more")
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn whole_numbers_are_taken_and_negative_or_broken_ones_refused_saying_why() {
        assert_eq!(count("20"), Ok(20));
        assert_eq!(seed("0"), Ok(0));
        assert_eq!(count("-1").unwrap_err(), "a count cannot be negative");
        assert_eq!(seed("-18446744073709551616").unwrap_err(), "a seed cannot be negative");
        for text in ["1.5", "ten", "", "18446744073709551616"] {
            assert_eq!(seed(text).unwrap_err(), "a seed is a whole number, 0 or more", "{text:?}");
        }
    }
}
