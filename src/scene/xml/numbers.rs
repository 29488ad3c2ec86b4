//! How Mitsuba writes numbers: lists separated by commas or white space, and finite
//! floats. Shared by the parser and the spectrum reader, which both read them.

/// Mitsuba's numbers are separated by commas and/or white space.
pub fn tokens(text: &str) -> impl Iterator<Item = &str> {
    text.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
}

/// A finite number, or `None`.
pub fn parse_f64(text: &str) -> Option<f64> {
    text.trim().parse::<f64>().ok().filter(|v| v.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_reject_text_and_non_finite() {
        assert_eq!(parse_f64(" 1.5e1 "), Some(15.0));
        assert_eq!(parse_f64("nan"), None);
        assert_eq!(parse_f64("inf"), None);
        assert_eq!(parse_f64("abc"), None);
        assert_eq!(tokens("1, 2 ,3").collect::<Vec<_>>(), ["1", "2", "3"]);
    }
}
