"""A JSON file a user passed, parsed; one line naming the file for each way reading it fails.

Every document fogbayes reads (fit, loop, prior, noise prior, chamber programme) comes through
:func:`read_json_file`, so a missing file, bytes that are not UTF-8, text that is not JSON and
nesting beyond the parser's stack are told the same way whichever command read them.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from ..errors import FogbayesError


def read_json_file(path: str | Path, what: str, fix: str, error=FogbayesError) -> Any:
    """The parsed JSON at ``path``.

    ``what`` names the document as the message's subject (``"the noise prior"``), ``fix`` is
    the message's fix, ``error`` the :class:`~fogbayes.errors.FogbayesError` subclass raised
    (called with the problem, ``file=`` and ``fix=``).
    """
    src = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise error(f"{what} does not exist", file=src, fix=fix) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise error(f"{what} cannot be read ({type(exc).__name__}: {exc})", file=src,
                    fix=fix) from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise error(f"{what} is not valid JSON ({exc.msg} at line {exc.lineno} column "
                    f"{exc.colno})", file=src, fix=fix) from None
    except (RecursionError, ValueError) as exc:  # nesting beyond the parser's stack; huge ints
        raise error(f"{what} cannot be parsed ({type(exc).__name__}: nested deeper than the "
                    "parser's stack or numbers too long)", file=src, fix=fix) from None
