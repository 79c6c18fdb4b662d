"""The fast path of kernels/jit.py: kernels linked into their callers, through Numba's internals.

A kernel called by kernels is compiled once per plain signature and only linked into its
callers (`_Kernel`; docs/architecture.md, "Compiling"), a compile to link can be handed over
from another process (`impactbeams.compilation`), and a ``borrowing_kernel`` compiles without
Numba's runtime (``_nrt=False``). All of it relies on Numba's compiler internals (dispatcher,
code library, compile results), checked with Numba 0.68 by ``tests/test_compile.py``; jit.py
imports this module only when this Numba has each of them (`jit.FAST_PATH_INTERNALS`), and
compiles plain ``numba.njit`` kernels otherwise.
"""

import pickle
from pathlib import Path

from llvmlite import binding as llvm
from numba import typeof
from numba.core import compiler, event, serialize, sigutils, typing
from numba.core import types as numba_types
from numba.core.codegen import JITCodeLibrary
from numba.core.compiler_lock import global_compiler_lock
from numba.core.environment import lookup_environment
from numba.core.registry import CPUDispatcher

from impactbeams.kernels.jit import COMPILE_WAIT


class _Kernel(CPUDispatcher):
    """A dispatcher that one kernel calling another compiles once per plain signature, to link.

    Numba types a call between kernels with its constant arguments as literals
    (``Literal[bool](True)``) and an omitted argument as its default: each combination would be
    compiled as its own specialisation, with every kernel it calls (``find_switch`` twice, for
    example). Typed by their plain types (the default's type for an omitted argument), the
    calls share one compile; the values are passed at run time, and the results are the same.

    A kernel compiled for a calling kernel is only linked into the caller's code: it gets no
    machine code, no Python or C wrappers and no cache entry of its own (a third of a cold
    compile's time), since its callers' machine code holds it and the kernels called from
    Python are cached with everything they call. A call from Python compiles it in full.
    """

    def get_call_template(self, args, kws):
        pysig, folded = self._compiler.fold_argument_types(args, kws)
        args = tuple(map(_plain_type, folded))
        if self._can_compile and args not in self.overloads:
            self._compile_to_link(args)
            _refuse_borrowed_returns(self, self.overloads[args].signature.return_type)
        name = self.py_func.__name__
        template = typing.make_concrete_template(f"CallTemplate({name})", key=name,
                                                 signatures=self.nopython_signatures)
        return template, pysig, args, {}

    def compile(self, sig):
        """Compile for a call from Python: in full, replacing a compile only to link."""
        args = tuple(sigutils.normalize_signature(sig)[0])
        _wait_elsewhere(self, args)
        existing = self.overloads.get(args)
        if existing is not None and isinstance(existing.entry_point, _LinkedEntry):
            del self.overloads[args]
        entry_point = super().compile(sig)
        _set_environments(self.overloads[args].library)
        return entry_point

    def link_into(self, args, path: Path) -> None:
        """Compile to link, as a calling kernel would, and write what a caller links to ``path``.

        Another process's compile then takes it over instead of compiling it (`_taken_over`):
        a helper process's share of a cold compile (`impactbeams.compilation`).
        """
        with global_compiler_lock, self._compiling_counter:
            handover = _handover(self._compile_linked(args))  # links its callees: locked
        path.write_bytes(handover)

    def _compile_to_link(self, args):
        handover = _wait_elsewhere(self, args)
        with global_compiler_lock, self._compiling_counter:
            cres = None if handover is None else _taken_over(self, handover)
            if cres is not None:
                self._link(args, cres)
                return
            cres = self._cache.load_overload(args, self.targetctx)  # a Python call's, cached
            if cres is not None:
                self.targetctx.insert_user_function(cres.entry_point, cres.fndesc,
                                                    [cres.library])
                self.add_overload(cres)
                return
            details = {"dispatcher": self, "args": args, "return_type": None}
            with event.trigger_event("numba:compile", data=details):
                self._link(args, self._compile_linked(args))

    def _link(self, args, cres):
        """Make ``cres``, a compile only to link, what kernels calling with ``args`` link."""
        self.targetctx.insert_user_function(cres.entry_point, cres.fndesc, [cres.library])
        self.overloads[args] = cres  # not callable from Python: `compile` replaces it

    def _compile_linked(self, args):
        flags = compiler.Flags()
        self.targetdescr.options.parse_as_flags(flags, self.targetoptions)
        flags.no_cpython_wrapper = flags.no_cfunc_wrapper = flags.no_compile = True
        library = _LinkedLibrary(self.targetctx.codegen(), self.py_func.__qualname__)
        cres = compiler.compile_extra(
            self.targetdescr.typing_context, self.targetctx, self.py_func, args=args,
            return_type=None, flags=flags, locals=self.locals, library=library,
            pipeline_class=self._compiler.pipeline_class)
        return cres._replace(entry_point=_LinkedEntry())


# (kernel, argument types) -> a function returning once another process has compiled it, or
# given up (`impactbeams.compilation`): the path of the file into which it handed over a
# compile to link (`_Kernel.link_into`), or None: the compile then loads it from the disk cache
COMPILED_ELSEWHERE = {}


def _wait_elsewhere(dispatcher, args):
    """Wait for another process's compile of ``dispatcher`` at ``args``, if it has one.

    The wait is this process's compile done elsewhere: a `jit.COMPILE_WAIT` event, which the
    compile report (`impactbeams.compilation.reporting_compiles`) announces, times and keeps
    alive as a compile (under load a helper's share took minutes, silent before: issue 32).
    """
    wait = COMPILED_ELSEWHERE.pop((dispatcher, args), None)
    if wait is None:
        return None
    details = {"dispatcher": dispatcher, "args": args, "return_type": None}
    with event.trigger_event(COMPILE_WAIT, data=details):
        return wait()


def _handover(cres):
    """What a caller links of a compile to link: its LLVM bitcode, how to call it, Environments."""
    fndesc = cres.fndesc
    fndesc.typemap = fndesc.calltypes = None  # typing details, unpicklable, unused by a call
    library = cres.library
    return serialize.dumps((library.name, library._get_module_for_linking().as_bitcode(), fndesc,
                            cres.environment, cres.signature,
                            tuple(cres._find_referenced_environments())))


def _taken_over(dispatcher, path):
    """The compile to link another process wrote to ``path`` (`_handover`); None if unreadable.

    The bitcode is the other process's compile as it is, so the caller links and optimises the
    same IR as had it compiled it itself; unpickling registers the Environments in this
    process, where the caller's compile points its globals at them (`_set_environments`).
    """
    try:
        name, bitcode, fndesc, environment, signature, environments = pickle.loads(
            Path(path).read_bytes())
    except Exception:  # a truncated or foreign file: compiled here instead
        return None
    library = _LinkedLibrary(dispatcher.targetctx.codegen(), name)
    library._final_module = llvm.parse_bitcode(bitcode)
    library._finalize_final_module()
    return compiler.CompileResult(
        typing_context=dispatcher.targetdescr.typing_context,
        target_context=dispatcher.targetctx, entry_point=_LinkedEntry(), typing_error=None,
        type_annotation=None, signature=signature, objectmode=False, lifted=(), fndesc=fndesc,
        library=library, call_helper=None, environment=environment, metadata=None,
        reload_init=(), referenced_envs=environments)


class _LinkedEntry:
    """The key under which a kernel compiled only to link is known to the target context."""


class _LinkedLibrary(JITCodeLibrary):
    """LLVM IR to link into callers' code, never turned into machine code itself.

    Its functions are optimised one by one (Numba's function passes) but not as a module:
    the calling kernel's module passes optimise everything it links, once, where each level
    of a call chain re-optimised all it linked. Measured: the same maps and simulate results,
    bit for bit, and Fig. 5a's run time within 1 %.
    """

    def _optimize_final_module(self):
        pass

    def _finalize_final_module(self):
        self._finalize_dynamic_globals()
        self._verify_declare_only_symbols()
        self._finalized = True


def _set_environments(library):
    """Point the Environment globals of the kernels ``library`` links at their Environments.

    Numba sets a kernel's global when it makes the kernel's machine code, which a linked kernel
    never gets; its code reads it to call Python (``print``): as a cache load does, set each.
    """
    for variable in library._final_module.global_variables:
        environment = lookup_environment(variable.name)
        if environment is not None:
            library.codegen.set_env(variable.name, environment)


def _refuse_borrowed_returns(dispatcher, returned):
    """A ``borrowing_kernel`` returns no array: its caller would release a reference not taken."""
    if dispatcher.targetoptions.get("_nrt", True):
        return
    pending = [returned]
    while pending:
        kind = pending.pop()
        if isinstance(kind, numba_types.ArrayCompatible):
            raise TypeError(f"{dispatcher.py_func.__qualname__} borrows its arrays and cannot "
                            f"return one ({returned}): make it an inlined_kernel")
        pending.extend(getattr(kind, "types", ()))


def _plain_type(argument):
    if isinstance(argument, numba_types.Omitted):
        return typeof(argument.value)
    return numba_types.unliteral(argument)


def linking_kernel(function, options: dict) -> CPUDispatcher:
    """``function`` as a kernel of the fast path, compiled with Numba's target ``options``."""
    dispatcher = _Kernel(py_func=function, locals={}, targetoptions=options)
    dispatcher.enable_caching()
    return dispatcher
