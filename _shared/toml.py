"""One TOML reader for every configuration file (the station's, the arm's)."""

from __future__ import annotations

__all__ = ["parse_toml"]


def parse_toml(raw: bytes, path, *, error: type[Exception] = ValueError) -> dict:
    """The TOML document in ``raw``, the bytes of the file at ``path``.

    Raises
    ------
    error
        Naming ``path``: the bytes are not UTF-8 text (UTF-16, a binary file, another encoding; the
        first bad byte and its offset are given) or not valid TOML. A byte-order mark, as some
        Windows editors write, is dropped.
    """
    import tomllib

    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        if raw[:2] in (b"\xff\xfe", b"\xfe\xff"):
            kind = "UTF-16 text"
        elif b"\0" in raw:
            kind = "a binary file"
        else:
            kind = "not UTF-8 text (saved as Latin-1 or another encoding?)"
        raise error(f"{path}: {kind}: byte 0x{raw[exc.start]:02x} at offset {exc.start}; a TOML file "
                    f"must be UTF-8 text") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{path}: not valid TOML ({exc})") from None
