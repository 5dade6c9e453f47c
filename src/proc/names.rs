//! What a name says: its words, for matching inputs to their roles
//! (`sunDirection` is a direction), and a new name made from an old one.

/// The words of a name, lowercase, a plural as its singular:
/// `sunDirection` gives `sun`, `direction`; `point_lights[0].color` gives
/// `point`, `light`, `color`.
pub fn name_words(name: &str) -> Vec<String> {
    let mut out = vec![String::new()];
    let mut previous_lower = false;
    for c in name.chars() {
        if !c.is_ascii_alphabetic() {
            out.push(String::new());
            previous_lower = false;
            continue;
        }
        if c.is_uppercase() && previous_lower {
            out.push(String::new());
        }
        previous_lower = c.is_lowercase();
        if let Some(last) = out.last_mut() {
            last.push(c.to_ascii_lowercase());
        }
    }
    out.retain(|w| !w.is_empty());
    for word in &mut out {
        // `lights` and `counts`, not `axis`, `radius` or `class`.
        let singular = ["ss", "is", "us"].iter().all(|end| !word.ends_with(end));
        if word.len() > 3 && word.ends_with('s') && singular {
            word.pop();
        }
    }
    out
}

/// `vs_main` → `VsMain`.
pub fn pascal(name: &str) -> String {
    name.split('_')
        .filter(|part| !part.is_empty())
        .map(|part| {
            let mut chars = part.chars();
            chars
                .next()
                .map(|c| c.to_uppercase().chain(chars).collect::<String>())
                .unwrap_or_default()
        })
        .collect()
}
