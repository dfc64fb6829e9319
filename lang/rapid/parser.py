"""The RAPID front end: a ``.mod`` file's text → the syntax tree of :mod:`.nodes`.

The grammar (``rapid.lark``) follows the RAPID kernel's syntax as ABB's "Technical
reference manual - RAPID kernel" (3HAC050946, RobotWare 6) and "RAPID overview" describe it;
what was read and what is unconfirmed is in :mod:`.tables`. A syntax error becomes one
problem ``SOURCE:LINE: what``; a block left open names the END keyword it lacks.

Operators bind, tightest first: ``* / DIV MOD``, ``+ -``, comparisons, ``NOT``, ``AND``,
``OR XOR`` (RAPID kernel, expressions: unconfirmed — where NOT falls is wirecal's reading).
Blocks deeper than :data:`MAX_BLOCK_DEPTH` and brackets deeper than
:data:`~wirecal.lang.syntax.MAX_BRACKET_DEPTH` (the three languages' one rule) are refused
before parsing, expressions nested deeper than
:data:`~wirecal.lang.syntax.MAX_EXPRESSION_DEPTH` (chained operators too) while parsing,
before anything recursive runs on them (the parser builds the expressions' nodes as it
reduces their rules; the statements' nodes are built from its tree afterwards).
"""

from __future__ import annotations

import io
import re
import threading
from collections.abc import Callable
from functools import cache, lru_cache, update_wrapper
from importlib import resources

from lark import Lark, Token, Transformer, Tree, v_args
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedToken

from wirecal.lang.rapid import nodes as N
from wirecal.lang.rapid.tables import RESERVED
from wirecal.lang.syntax import (
    BRACKET_PROBLEM,
    MAX_BRACKET_DEPTH,
    MAX_EXPRESSION_DEPTH,
    OPERATOR_RUN_PROBLEM,
    RUN_TOKENS,
    OperatorRun,
)

_ENDS = {
    "ENDPROC": "PROC",
    "ENDFUNC": "FUNC",
    "ENDTRAP": "TRAP",
    "ENDIF": "IF",
    "ENDFOR": "FOR",
    "ENDWHILE": "WHILE",
    "ENDTEST": "TEST",
    "ENDMODULE": "MODULE",
    "ENDRECORD": "RECORD",
}


class SyntaxProblem(Exception):
    """A module the grammar does not read: ``line`` and ``message``."""

    def __init__(self, line: int, message: str):
        super().__init__(message)
        self.line, self.message = line, message


def _lark(transformer: Transformer | None) -> Lark:
    """Return a parser of the grammar that applies ``transformer`` as it reduces each rule."""
    grammar = resources.files(__package__).joinpath("rapid.lark").read_text(encoding="utf-8")
    return Lark(
        grammar,
        parser="lalr",
        lexer="basic",
        propagate_positions=True,
        maybe_placeholders=True,
        transformer=transformer,
    )


@cache
def _parser() -> Lark:
    """Return the parser that builds a module's expressions as it parses (:class:`_Expressions`).

    The statements and declarations stay lark trees, their source lines propagated from
    their first token (``propagate_positions``), and :class:`_Build` makes them nodes.
    """
    return _lark(_expressions)


@cache
def _tree_parser() -> Lark:
    """Return the parser that keeps every expression a lark tree: where one nests too deep.

    :func:`_parser`'s grammar, lexer and tables without its transformer, copied in memory
    (``Lark.save`` and ``Lark.load``: 0.02 s of CPU, where building them again took 0.16 s).
    """
    saved = io.BytesIO()
    _parser().save(saved, exclude_options=("transformer",))
    saved.seek(0)
    return Lark.load(saved)


def _string(text: str) -> str:
    r"""Resolve a RAPID string literal's escapes: ``""`` is ", ``\\`` is \, ``\hh`` a code."""
    body, out, i = text[1:-1], [], 0
    while i < len(body):
        if body[i] == '"':
            out.append('"')
            i += 2
        elif body[i] == "\\" and body[i + 1] == "\\":
            out.append("\\")
            i += 2
        elif body[i] == "\\":
            out.append(chr(int(body[i + 1 : i + 3], 16)))
            i += 3
        else:
            out.append(body[i])
            i += 1
    return "".join(out)


class _TooDeep(Exception):
    """An expression nests deeper than :data:`MAX_EXPRESSION_DEPTH` (:func:`_parsed` says where)."""


_Rule = Callable[["_Expressions", list], object]


def _nesting(build: _Rule) -> _Rule:
    """Make ``build``, an expression rule's callback, count the rule's levels as it builds.

    A node's level is one more than its deepest child's (a node of another rule, or a
    token, is level 0), as :func:`_expression_depth` counts down a tree: the chain of
    expression rules nested in each other. Beyond :data:`MAX_EXPRESSION_DEPTH` it raises
    :class:`_TooDeep`, before anything recursive runs on the nodes.
    """

    def counted(self: _Expressions, c: list) -> object:
        node = build(self, c)
        levels = self.levels
        level = 1 + max((levels[id(x)][0] for x in c if id(x) in levels), default=0)
        if level > MAX_EXPRESSION_DEPTH:
            raise _TooDeep
        levels[id(node)] = (level, node)  # keeps the node, so no other object takes its id
        return node

    return update_wrapper(counted, build)


class _Expressions(Transformer):
    """The expression rules → nodes, called by the parser as it reduces each rule.

    Names stay lark tokens until a rule takes them (the statements' source lines are
    propagated from their first token). ``levels``: each expression node built in the
    current parse by ``id``, with its level (:func:`_nesting`); emptied after each parse.
    """

    def __init__(self) -> None:
        super().__init__()
        self._threads = threading.local()  # one parser, its parses in any thread

    @property
    def levels(self) -> dict[int, tuple[int, object]]:
        """The current thread's expression nodes of its current parse, by ``id``."""
        try:
            return self._threads.levels
        except AttributeError:
            self._threads.levels = {}
            return self._threads.levels

    def number(self, c):
        text = str(c[0])
        return N.Num(float(text), text.isdigit())

    def string(self, c):
        return N.Str(_string(str(c[0])))

    def boolean(self, c):
        return N.Bool(str(c[0]).upper() == "TRUE")

    def name(self, c):
        return N.Name(str(c[0]))

    @_nesting
    def component(self, c):
        return N.Component(c[0], str(c[1]))

    @_nesting
    def index(self, c):
        return N.Index(c[0], c[1:])

    @_nesting
    def aggregate(self, c):
        return N.Aggregate(list(c))

    @_nesting
    def binop(self, c):
        op = str(c[1])
        return N.BinOp(op.upper() if op.isalpha() else op, c[0], c[2])

    @_nesting
    def signed(self, c):
        return N.Neg(c[1]) if str(c[0]) == "-" else c[1]

    @_nesting
    def not_op(self, c):
        return N.Not(c[1])

    @_nesting
    def funcall(self, c):
        return N.FuncCall(str(c[0]), c[1] or [])

    @_nesting
    def args(self, c):
        return list(c)

    @_nesting
    def arg(self, c):
        return N.Arg(c[0])

    @_nesting
    def named_arg(self, c):
        return N.Arg(c[1], str(c[0]), named=True)

    @_nesting
    def opt_arg(self, c):
        return N.Arg(c[1], str(c[0]))

    def cond_arg(self, c):
        return N.Arg(None, str(c[0]), condition=str(c[1]))


_expressions = _Expressions()


@v_args(meta=True)
class _Build(Transformer):
    """The statements' and declarations' lark trees → nodes (their source line from ``meta``)."""

    def NAME(self, t: Token) -> str:
        return str(t)

    def placeholder(self, meta, c):
        return N.Placeholder(str(c[0]), meta.line)

    def mode(self, meta, c):
        return str(c[0]).upper()

    storage = mode

    def dims(self, meta, c):
        return list(c)

    def data_decl(self, meta, c):
        scope, storage, type_, name, dims, init = c
        local = str(scope or "").upper() == "LOCAL"
        return N.Data(storage, type_, name, dims or [], init, meta.line, local)

    def component_sel(self, meta, c):
        return ("component", c[0])

    def index_sel(self, meta, c):
        return ("index", list(c))

    def target(self, meta, c):
        node: N.Expr = N.Name(c[0])
        for kind, what in c[1:]:
            node = N.Component(node, what) if kind == "component" else N.Index(node, what)
        return node

    def assign(self, meta, c):
        return N.Assign(c[0], c[1], meta.line)

    def call_stmt(self, meta, c):
        return N.Call(c[0], c[1] or [], meta.line)

    def elseif(self, meta, c):
        return (c[0], list(c[1:]))

    def else_part(self, meta, c):
        return ("else", list(c))

    def if_stmt(self, meta, c):
        cond, *rest = [x for x in c if x is not None]
        body = [s for s in rest if not isinstance(s, tuple)]
        branches = [(cond, body)] + [b for b in rest if isinstance(b, tuple) and b[0] != "else"]
        orelse = next((b[1] for b in rest if isinstance(b, tuple) and b[0] == "else"), [])
        return N.If(branches, orelse, meta.line)

    def compact_if(self, meta, c):
        return N.If([(c[0], [c[1]])], [], meta.line)

    def for_stmt(self, meta, c):
        var, start, stop, step, *body = c
        return N.For(var, start, stop, step, body, meta.line)

    def while_stmt(self, meta, c):
        return N.While(c[0], list(c[1:]), meta.line)

    def case(self, meta, c):
        values = [x for x in c if not isinstance(x, N.Stmt)]
        return (values, [x for x in c if isinstance(x, N.Stmt)])

    def default(self, meta, c):
        return ("default", list(c))

    def test_stmt(self, meta, c):
        expr, *rest = [x for x in c if x is not None]
        cases = [x for x in rest if isinstance(x, tuple) and x[0] != "default"]
        default = next((x[1] for x in rest if isinstance(x, tuple) and x[0] == "default"), [])
        return N.Test(expr, cases, default, meta.line)

    def return_stmt(self, meta, c):
        return N.Return(c[0], meta.line)

    def exit_stmt(self, meta, c):
        return N.Exit(meta.line)

    def goto_stmt(self, meta, c):
        return N.Goto(c[0], meta.line)

    def raise_stmt(self, meta, c):
        return N.Raise(c[0], meta.line)

    def retry_stmt(self, meta, c):
        return N.Resume("RETRY", meta.line)

    def trynext_stmt(self, meta, c):
        return N.Resume("TRYNEXT", meta.line)

    def connect_stmt(self, meta, c):
        return N.Connect(c[0], c[1], meta.line)

    def late_call(self, meta, c):
        return N.LateCall(c[0], c[1] or [], meta.line)

    def label(self, meta, c):
        return N.Label(c[0], meta.line)

    def handler(self, meta, c):
        return ("handler", str(c[0]).upper(), [x for x in c[1:] if isinstance(x, N.Stmt)])

    def body(self, meta, c):
        return [s for s in c if isinstance(s, N.Stmt)], [h for h in c if isinstance(h, tuple)]

    def _routine(self, kind, name, type_, params, body, line, local):
        stmts, handlers = body
        out = N.Routine(kind, name, type_, params or [], stmts, None, line, local is not None)
        for _, which, handler in handlers:
            if which == "ERROR":
                out.handler = handler
            else:
                out.other_handlers[which] = handler
        return out

    def proc(self, meta, c):
        return self._routine("PROC", c[1], None, c[2], c[3], meta.line, c[0])

    def func(self, meta, c):
        return self._routine("FUNC", c[2], c[1], c[3], c[4], meta.line, c[0])

    def trap(self, meta, c):
        return self._routine("TRAP", c[1], None, None, c[2], meta.line, c[0])

    def params(self, meta, c):
        return list(c)

    def pdims(self, meta, c):
        return sum(str(t) == "*" for t in c)

    def param(self, meta, c):
        mode, type_, name, dims = c
        return N.Param(name, type_, mode or "", False, int(dims or 0), meta.line)

    def opt_param(self, meta, c):
        mode, type_, name, dims, *alternatives = c
        pairs = list(zip(alternatives[::2], alternatives[1::2], strict=True))
        return N.Param(name, type_, mode or "", True, int(dims or 0), meta.line, pairs)

    def record(self, meta, c):
        return ("RECORD", c[0], tuple(c[1:]), meta.line)

    def data_field(self, meta, c):
        return (c[1], c[0])

    def alias(self, meta, c):
        return ("ALIAS", c[1], c[0], meta.line)

    def attrs(self, meta, c):
        return list(c)

    def module(self, meta, c):
        name, attrs, *items = c
        module = N.Module(name, attrs or [], [], [])
        for item in items:
            if isinstance(item, N.Data):
                module.data.append(item)
            elif isinstance(item, N.Routine):
                module.routines.append(item)
            else:
                kind, type_name, what, line = item
                types = module.records if kind == "RECORD" else module.aliases
                types[type_name] = what
                module.unsupported.append(N.Unsupported(f"{kind} {type_name}", line, type_name))
        return module

    def start(self, meta, c):
        return c[0]


MAX_BLOCK_DEPTH = 64
"""Deepest nesting of blocks (IF, FOR, WHILE, TEST) wirecal reads; wirecal's bound, far
beyond its modules (the controller's own limit is unconfirmed)."""


def _too_deep(text: str) -> SyntaxProblem | None:
    """Refuse up front what the parser would take too long or recurse too deep on.

    One pass over the tokens counts the runs of operators
    (:class:`~wirecal.lang.syntax.OperatorRun`), the brackets and the blocks. A run of more
    than :data:`~wirecal.lang.syntax.MAX_OPERATOR_RUN` operators is named first, wherever it
    is (parsing it would take minutes); else the first nesting beyond the bounds.
    """
    run = OperatorRun()
    nesting = _Nesting()
    deep: SyntaxProblem | None = None
    for number, source_line in enumerate(text.splitlines(), 1):
        for m in _TOKEN.finditer(source_line):
            word = m.group().upper()
            if word in RUN_TOKENS and run.see(word):
                return SyntaxProblem(number, OPERATOR_RUN_PROBLEM)
            if deep is None:
                deep = nesting.see(word, number)
    return deep


class _Nesting:
    """The brackets and blocks open so far, token by token (:func:`_too_deep`)."""

    def __init__(self) -> None:
        self.brackets = 0
        self.blocks = 0

    def see(self, word: str, number: int) -> SyntaxProblem | None:
        """Count one token (upper case) of line ``number``; the problem if nested too deep."""
        if word in ("(", "[", "{"):
            self.brackets += 1
            if self.brackets > MAX_BRACKET_DEPTH:
                return SyntaxProblem(number, BRACKET_PROBLEM)
        elif word in (")", "]", "}"):
            self.brackets -= 1
        elif word in ("THEN", "FOR", "WHILE", "TEST"):
            self.blocks += 1
            if self.blocks > MAX_BLOCK_DEPTH:
                return SyntaxProblem(
                    number,
                    f"blocks nested more than {MAX_BLOCK_DEPTH} deep: wirecal reads at most "
                    f"{MAX_BLOCK_DEPTH}",
                )
        elif word in ("ENDIF", "ENDFOR", "ENDWHILE", "ENDTEST") and self.blocks:
            self.blocks -= 1
        return None


_TOKEN = re.compile(r'"(?:[^"\n]|"")*"|![^\n]*|[A-Za-z][A-Za-z0-9_]*|[()\[\]{},;]|[-+*/<>=]')


_HEADER = re.compile(r"\A\s*%%%[^\n]*\n(?:(?!%%%)[^\n]*\n)*?\s*%%%[^\n]*(?=\n|\Z)")
"""The header a controller writes before a saved module (``%%%``, ``VERSION:1``,
``LANGUAGE:ENGLISH``, ``%%%``): modules saved by IRC5 controllers start with it (e.g.
SDEBEUL/Kraker1@5a5835c, HOME/linked_m.sys, from a RobotWare 5 backup); its meaning is
unconfirmed (no page read), wirecal reads past it."""


def _without_header(text: str) -> str:
    """Blank the controller's ``%%%`` header, keeping the line numbers."""
    m = _HEADER.match(text)
    return text if m is None else "\n" * m.group().count("\n") + text[m.end() :]


def _binary(text: str) -> bool:
    """Whether ``text`` is no RAPID text (an encrypted module: NUL or control bytes)."""
    head = text[:4096]
    controls = sum(1 for ch in head if ord(ch) < 32 and ch not in "\t\n\r\f")
    return controls > max(2, len(head) // 100)


def parse_module(text: str) -> N.Module:
    """Parse one module's text; raise :class:`SyntaxProblem` where the grammar stops.

    The last modules parsed are kept (nothing changes a parsed module), long and short
    apart so that neither pushes out the other: the last 32 of :data:`SHORT_MODULE_CHARS`
    or more (a generated module is checked by the generator, then run in the twin several
    times; about 1 MB kept, 0.15 s to parse) and the last 256 shorter ones (a few kB kept
    each, about 5 ms to parse: with 32 slots for all, a process checking many short
    modules parsed the same ones again).
    """
    return (_parse_long if len(text) >= SHORT_MODULE_CHARS else _parse_short)(text)


SHORT_MODULE_CHARS = 10_000
"""A module's text shorter than this is kept among the short ones (:func:`parse_module`)."""


def _parse(text: str) -> N.Module:
    """Parse one module's text (see :func:`parse_module`)."""
    if _binary(text):
        raise SyntaxProblem(
            1,
            "not RAPID text (control bytes): an encrypted or encoded module, which "
            "wirecal cannot read; check the other modules with --external-calls",
        )
    text = _without_header(text)
    deep = _too_deep(text)
    if deep is not None:
        raise deep
    try:
        tree = _parsed(text)
    except UnexpectedToken as e:
        raise SyntaxProblem(
            e.line if e.line > 0 else _last_line(text), _unexpected(e, text)
        ) from None
    except UnexpectedCharacters as e:
        what = (
            "a string not closed on its line"
            if e.char == '"'
            else f"unexpected character {e.char!r}"
        )
        raise SyntaxProblem(e.line, what) from None
    except UnexpectedEOF:
        raise SyntaxProblem(_last_line(text), _missing(text, 0, "the end of the file")) from None
    try:
        return _Build().transform(tree)
    except Exception as e:  # lark wraps a SyntaxProblem raised in a callback
        inner = getattr(e, "orig_exc", e)
        if isinstance(inner, SyntaxProblem):
            raise inner from None
        raise


def _parsed(text: str) -> Tree:
    """Return the module's tree, its expressions built; raise lark's exception where it stops.

    An expression nested too deep is refused as the tree of every expression says
    (:func:`_expression_depth`: its line, after any syntax error later in the text).
    """
    levels = _expressions.levels
    try:
        return _parser().parse(text)
    except _TooDeep:
        levels.clear()
        _expression_depth(_tree_parser().parse(text))
        raise AssertionError("an expression counted too deep is not in the tree") from None
    finally:
        levels.clear()


_parse_long = lru_cache(maxsize=32)(_parse)
_parse_short = lru_cache(maxsize=256)(_parse)

_EXPRESSIONS = frozenset(n for n, f in vars(_Expressions).items() if hasattr(f, "__wrapped__"))
"""The parse tree's expression nodes, the rules :func:`_nesting` counts (binop, signed,
not_op, component, index, funcall, aggregate, args, arg, named_arg, opt_arg): the checker
recurses per level."""


def _expression_depth(tree: Tree) -> None:
    """Refuse an expression nested deeper than :data:`MAX_EXPRESSION_DEPTH`, without recursion.

    A chain of operators nests one level per operator (``a + a + … + a``), as parentheses do.
    """
    stack: list[tuple[Tree, int]] = [(tree, 0)]
    while stack:
        node, depth = stack.pop()
        depth = depth + 1 if node.data in _EXPRESSIONS else 0
        if depth > MAX_EXPRESSION_DEPTH:
            raise SyntaxProblem(
                node.meta.line,
                f"an expression nested more than {MAX_EXPRESSION_DEPTH} levels deep "
                "(parentheses or chained operators); wirecal reads at most "
                f"{MAX_EXPRESSION_DEPTH}: split the expression",
            )
        stack.extend((c, depth) for c in node.children if isinstance(c, Tree))


def _last_line(text: str) -> int:
    return max(1, text.rstrip().count("\n") + 1)


def _unexpected(e: UnexpectedToken, text: str) -> str:
    """Say what the parser found and, at an END keyword, which block is left open."""
    found = "the end of the file" if e.token.type == "$END" else repr(str(e.token))
    word = str(e.token).upper()
    if word == "MODULE" and "$END" in e.expected:
        return "a second MODULE: one module per file"
    if set(e.expected) == {"$END"}:
        return f"{found} after ENDMODULE: a file holds one module and nothing after it"
    if word in RESERVED and word not in _ENDS and "NAME" in e.expected:
        return (
            f"{e.token} is a RAPID reserved word: it cannot be a name "
            "(RAPID kernel, reserved words: unconfirmed)"
        )
    if e.token.type == "$END" or str(e.token).upper() in _ENDS:
        return _missing(text, e.line if e.token.type != "$END" else 0, found)
    names = ", ".join(sorted(_readable(x) for x in e.expected)[:8])
    return f"syntax error at {found}; expected {names}"


_WORD = re.compile(r'"(?:[^"\n]|"")*"|![^\n]*|[A-Za-z][A-Za-z0-9_]*|;')


def _missing(text: str, line: int, found: str) -> str:
    """Name the innermost block still open before ``line`` (0: the end), or a syntax error."""
    stack: list[tuple[str, int]] = []
    pending_if: int | None = None
    for number, source_line in enumerate(text.splitlines(), 1):
        if line and number >= line:
            break
        for m in _WORD.finditer(source_line):
            word = m.group().upper()
            if word == "IF":
                pending_if = number
            elif word == "THEN" and pending_if is not None:
                stack.append(("IF", pending_if))
                pending_if = None
            elif word == ";":
                pending_if = None
            elif word in _OPENERS:
                stack.append((word, number))
            elif word in _ENDS and stack and stack[-1][0] == _ENDS[word]:
                stack.pop()
    if not stack:
        return f"syntax error at {found}"
    opener, where = stack[-1]
    end = next(k for k, v in _ENDS.items() if v == opener)
    return f"{opener} (line {where}) without its {end}: found {found}"


_OPENERS = {"MODULE", "PROC", "FUNC", "TRAP", "FOR", "WHILE", "TEST", "RECORD"}


def _readable(terminal: str) -> str:
    return {"SEMICOLON": "';'", "NAME": "a name", "LPAR": "'('", "RPAR": "')'"}.get(
        terminal, terminal
    )
