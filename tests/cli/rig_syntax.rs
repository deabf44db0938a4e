//! A rig that is not TOML, from the command line: the message points at
//! the line and column of the cause and names no field.

use crate::common::caveray;

#[test]
fn a_rig_with_an_unclosed_bracket_is_reported_where_it_opened() {
    let dir = std::env::temp_dir().join(format!("caveray-rig-syntax-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let good = std::fs::read_to_string("cave_configs/powerwall.toml").unwrap();
    let cases = [
        // The parser gives up on the line after (as a missing comma in
        // the next field); the cause is the '[' of line 22.
        (
            good.replacen("ll = [-2, 0.4, 0]", "ll = [-2, 0.4, 0", 1),
            "22:6: unclosed '[': the array opened here is not closed before line 23 (expected `]`)",
        ),
        (
            good.replacen("name = \"wall\"", "name = \"wall", 1),
            "21:8: unclosed string: the \" here is not closed on its line",
        ),
        (
            good.replacen("size = 1.2", "size = 1.2\nsize = 1.3", 1),
            "19:1: duplicate key `size` (first set on line 18)",
        ),
    ];
    for (i, (text, message)) in cases.iter().enumerate() {
        let rig = dir.join(format!("bad{i}.toml"));
        std::fs::write(&rig, text).unwrap();
        let r = rig.to_str().unwrap();
        let result = caveray(&["inspect", "--config", r]);
        let err = String::from_utf8(result.stderr).unwrap();
        assert_eq!(result.status.code(), Some(2), "{err}");
        assert_eq!(err, format!("caveray: {r}:{message}\n"));
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
