"""Exceptions raised for bad input.

Every error a user can cause by handing fogbayes a bad file or a bad argument is a
subclass of :class:`FogbayesError`, itself a :class:`ValueError`. The message names the
file, the column and the row where known, and says how to fix the problem; the command
line prints it as one line on stderr and exits with code 2.
"""

from __future__ import annotations


class FogbayesError(ValueError):
    """Base class of fogbayes input errors.

    Attributes:
        file: the file the problem is in (None for in-memory data).
        column: the column concerned, if any.
        row: 0-based data row (the first row after the header is row 0), if any.
        fix: one sentence saying how to fix it.
    """

    def __init__(
        self,
        problem: str,
        *,
        file: str | None = None,
        column: str | None = None,
        row: int | None = None,
        fix: str | None = None,
    ):
        self.problem = problem
        self.file = file
        self.column = column
        self.row = row
        self.fix = fix
        super().__init__(self._compose())

    def _compose(self) -> str:
        where = []
        if self.file is not None:
            where.append(f"{self.file}")
        if self.column is not None:
            where.append(f"column '{self.column}'")
        if self.row is not None:
            # Data row r sits on line r + 2 of a CSV file with one header line.
            where.append(f"row {self.row} (line {self.row + 2})")
        head = ": ".join([", ".join(where), self.problem]) if where else self.problem
        return f"{head}. Fix: {self.fix}" if self.fix else head


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
