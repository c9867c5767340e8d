"""Exceptions raised for bad input.

Every error a user can cause by handing fogbayes a bad file or a bad argument is a
subclass of :class:`FogbayesError`, itself a :class:`ValueError`. The message names the
file, the place in it (a table's column and row, a JSON document's field) or the
command-line option where known, and says how to fix the problem; the command line prints
it as one line on stderr and exits with code 2.
"""

from __future__ import annotations

from contextlib import contextmanager


class FogbayesError(ValueError):
    """Base class of fogbayes input errors.

    Attributes:
        file: the file the problem is in (None for in-memory data).
        column: the name concerned, if any: a column of a table, or, given as ``field=``,
            ``flag=`` or ``argument=``, a document field, a command-line option (a name
            starting with ``-`` is an option whichever keyword brought it) or a function's
            argument.
        kind: what ``column`` names, as the message says it: ``"column"``, ``"field"`` (a
            key of a JSON document or of metadata, dotted path), ``"option"`` or
            ``"argument"``.
        row: 0-based data row (the first row after the header is row 0), if any.
        fix: one sentence saying how to fix it.
        line: the 1-based physical line of the file (CSV: counting the ``# key: value``
            lines, the header and blank lines), where known.
    """

    def __init__(
        self,
        problem: str,
        *,
        file: str | None = None,
        column: str | None = None,
        row: int | None = None,
        fix: str | None = None,
        line: int | None = None,
        field: str | None = None,
        flag: str | None = None,
        argument: str | None = None,
    ):
        self.problem = problem
        self.file = file
        named = [v for v in (column, field, flag, argument) if v is not None]
        self.column = named[0] if named else None
        self.kind = ("option" if flag is not None or str(self.column).startswith("-")
                     else "field" if field is not None
                     else "argument" if argument is not None and column is None else "column")
        self.row = row
        self.fix = fix
        self.line = line
        super().__init__(self._compose())

    def _compose(self) -> str:
        where = []
        if self.file is not None:
            where.append(f"{self.file}")
        if self.column is not None:
            where.append(f"{self.kind} '{self.column}'")
        if self.row is not None:
            # the physical line (1-based, every line counted: metadata, header, blank lines)
            # is known only where the row was read from a text file; see ``located``
            where.append(f"row {self.row}" + (f" (line {self.line})" if self.line else ""))
        elif self.line is not None:
            where.append(f"line {self.line}")
        head = ": ".join([", ".join(where), self.problem]) if where else self.problem
        text = f"{head}. Fix: {self.fix}" if self.fix else head
        return " ".join(text.splitlines())  # one line on stderr, whatever the parts hold

    def located(self, *, file: str | None = None, line: int | None = None) -> "FogbayesError":
        """Fill in the file and/or the physical line where they were not known; returns self."""
        if file is not None and self.file is None:
            self.file = str(file)
        if line is not None and self.line is None:
            self.line = int(line)
        self.args = (self._compose(),)
        return self


class FileFormatError(FogbayesError):
    """The file cannot be read at all (unknown extension, unparsable, not a table)."""


class EmptyRecordingError(FogbayesError):
    """The file or array holds no data rows."""


class MissingColumnError(FogbayesError):
    """A required column is absent (often misnamed)."""


class NonNumericError(FogbayesError):
    """A cell that must be a number is not."""


class NonFiniteError(FogbayesError):
    """A cell is NaN, empty or infinite."""


class TimeOrderError(FogbayesError):
    """Time stamps are not strictly increasing (duplicates or steps back)."""


class TooShortError(FogbayesError):
    """The recording is too short for the analysis asked for."""


class UnitError(FogbayesError):
    """An unknown unit, or a unit that needs a scale factor that was not given."""


class ShapeError(FogbayesError):
    """Arrays handed to a Recording do not have matching lengths or shapes."""


class ArgumentError(FogbayesError):
    """An argument value is invalid (a window, an order, a method or scenario name)."""


class MissingExtraError(FogbayesError):
    """An optional package is not installed (Parquet: pyarrow; ``--engine dask``:
    distributed); the fix names the extra that installs it (:mod:`fogbayes.support.extras`)."""


class DuplicateColumnError(FileFormatError):
    """Two columns of a file have the same name (one would silently hide the other)."""


class RaggedRowError(FileFormatError):
    """A CSV row has more or fewer fields than the header (its cells would shift)."""


class MetadataError(FileFormatError):
    """A metadata value (``# key: value`` line, Parquet/NPZ metadata) is invalid."""


class ImplausibleValueError(FogbayesError):
    """Values that are numbers but physically implausible (wrong unit or scale)."""


#: The errors about a recording's data: :func:`about_file` names the file in them.
DATA_ERRORS = (EmptyRecordingError, MissingColumnError, NonNumericError, NonFiniteError,
               TimeOrderError, TooShortError, UnitError, ShapeError, ImplausibleValueError)


@contextmanager
def about_file(file):
    """Name ``file`` in the data errors raised inside that name no file.

    Array-level code (Allan deviation, block grids, least squares) raises
    :class:`TooShortError` or :class:`UnitError` without knowing where the data came
    from; a caller that does wraps the work: ``with about_file(rec.meta.source): ...``.
    """
    try:
        yield
    except DATA_ERRORS as exc:
        if file is not None and exc.file is None:
            exc.located(file=str(file))
        raise
