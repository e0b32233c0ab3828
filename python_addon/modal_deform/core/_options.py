"""The native core's option tables (cpp/util/option.h) in Python.

Each option is declared once, in C++, with its keyword, default, accepted range and meaning; the
bindings export the tables. Here they become the API's keyword-only parameters (``takes_options``:
the signature ``inspect.signature`` and ``help`` show, and a docstring section), and the add-on
reads its properties' defaults, limits and tooltips from the same records. The core checks every
value, so nothing here re-checks one.
"""

import functools
import inspect
import math
import warnings
from typing import NamedTuple


class Option(NamedTuple):
    """One option: ``default`` is None for an array (none given) and for an unbounded budget."""

    name: str
    default: object
    kind: str  # "int", "float", "bool", "energy" or "array"
    doc: str
    min: float
    max: float
    min_open: bool
    max_open: bool

    def range_text(self):
        """The accepted values in words ("at least 1", "in (0, 1)"), or "" when any value is."""
        low, high = math.isfinite(self.min), math.isfinite(self.max)
        if low and high:
            return (
                f"in {'(' if self.min_open else '['}{_number(self.min)}, {_number(self.max)}"
                f"{')' if self.max_open else ']'}"
            )
        if low:
            return f"{'more than' if self.min_open else 'at least'} {_number(self.min)}"
        if high:
            return f"{'less than' if self.max_open else 'at most'} {_number(self.max)}"
        return ""


def _number(x):
    return str(int(x)) if float(x).is_integer() and abs(x) < 1e6 else f"{x:g}"


def table(records):
    """{name: Option} of a native table (a list of records), in its order."""
    options = {}
    for record in records:
        record = dict(record)
        if record["default"] == math.inf:
            record["default"] = None
        options[record["name"]] = Option(**record)
    return options


#: Keywords that existing scripts use for an option since renamed: old name -> option name.
ALIASES = {"stiffness": "pull"}


def takes_options(*tables, exclude=()):
    """Decorator: ``function(*own_parameters, **options)`` takes the options of ``tables`` (dicts
    from ``table``) as keyword-only parameters with the core's defaults, but for the names in
    ``exclude``. Only the options a call names reach ``function`` (the core fills in the rest); a
    None given for an option whose default is None (an array, an unbounded budget) is dropped. An
    alias (ALIASES) is renamed, with a DeprecationWarning."""
    options = {name: option for t in tables for name, option in t.items() if name not in exclude}

    def decorate(function):
        own = [
            p for p in inspect.signature(function).parameters.values() if p.kind != p.VAR_KEYWORD
        ]
        parameters = own + [
            inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY, default=option.default)
            for name, option in options.items()
        ]
        signature = inspect.Signature(parameters)

        @functools.wraps(function)
        def with_options(*args, **keywords):
            for old, new in ALIASES.items():
                if old in keywords and new in options:
                    if new in keywords:
                        raise TypeError(
                            f"{function.__name__}() got both {new!r} and its old name {old!r}"
                        )
                    warnings.warn(
                        f"{function.__name__}: {old!r} is now called {new!r}",
                        DeprecationWarning,
                        stacklevel=2,
                    )
                    keywords[new] = keywords.pop(old)
            bound = signature.bind(*args, **keywords)
            given = {
                name: value
                for name, value in bound.arguments.items()
                if name in options and not (value is None and options[name].default is None)
            }
            own_arguments = {
                name: value for name, value in bound.arguments.items() if name not in options
            }
            return function(**own_arguments, **given)

        with_options.__signature__ = signature
        with_options.__doc__ = (
            (function.__doc__ or "").rstrip() + "\n\n" + _options_section(options)
        )
        return with_options

    return decorate


def _options_section(options):
    lines = ["    Options (keyword-only; their defaults and ranges are the native core's):"]
    for option in options.values():
        accepted = option.range_text()
        lines.append(
            f"        {option.name}={option.default!r}: {option.doc}"
            + (f" ({accepted})" if accepted else "")
        )
    return "\n".join(lines) + "\n"
