//! The one line `raykit` prints for a failed command: the error and its
//! causes joined by ": ", without the repetitions of a chain whose links
//! write their cause or their file into their own text.

/// `e` and its causes, joined by ": ". A cause whose text the line already
/// holds is left out (an error that writes its cause into its message and
/// also keeps it as its source), and a cause's leading `NAME: ` is dropped
/// where the line already names NAME (a file named by the context and by
/// the I/O error both).
pub fn error_message(e: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if line.contains(&text) {
            continue;
        }
        let text = match text.split_once(": ") {
            Some((name, rest)) if !line.is_empty() && line.contains(name) => rest.to_string(),
            _ => text,
        };
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    line
}

#[cfg(test)]
mod tests {
    use super::*;
    use anyhow::Context;

    #[test]
    fn repeated_causes_and_names_are_said_once() {
        let io = || std::io::Error::new(std::io::ErrorKind::NotFound, "No such file");
        // The cause written into the message and kept as the source.
        #[derive(Debug)]
        struct Load(std::io::Error);
        impl std::fmt::Display for Load {
            fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                write!(f, "m.obj: cannot read the file: {}", self.0)
            }
        }
        impl std::error::Error for Load {
            fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
                Some(&self.0)
            }
        }
        let e = anyhow::Error::new(Load(io()));
        assert_eq!(
            error_message(&e),
            "m.obj: cannot read the file: No such file"
        );
        // A context naming the file over an error naming it again.
        let e = Err::<(), _>(std::io::Error::other("d.bin: No space left on device"))
            .context("cannot write d.bin")
            .unwrap_err();
        assert_eq!(
            error_message(&e),
            "cannot write d.bin: No space left on device"
        );
        // Distinct causes stay.
        let e = Err::<(), _>(io()).context("loading the scene").unwrap_err();
        assert_eq!(error_message(&e), "loading the scene: No such file");
    }
}
