"""Two-level designed experiments: full and fractional factorials, their defining relation, resolution and
aliases (``two_level``), and the analysis of a response over the design's runs (``analyse``): each factor's
main effect and the two-factor interactions the design resolves, with confidence intervals from the
replicas (pure error), the design's unused contrasts, or, where the design is saturated, Lenth's pseudo
standard error.

Notation (Box, Hunter & Hunter, *Statistics for Experimenters*, 2nd ed., 2005, ch. 5-6; Montgomery,
*Design and Analysis of Experiments*, 8th ed., 2013, ch. 6-8): factor k is coded -1 (low) / +1 (high) and
lettered A, B, C, ... (I skipped); a 2^(k-p) fraction runs the full factorial of its first k - p factors
in standard (Yates) order and sets each of the other p by a generator, e.g. ``E = ABC``. The defining
relation is the group of words the generators span (``I = ABCE = ...``); its shortest word's length is the
resolution (III: mains aliased with two-factor interactions; IV: mains clear of them, two-factor
interactions aliased with each other; V: both clear). An effect is the mean response at +1 less the mean at
-1 (twice the regression coefficient on the coded column).

Pure Python and NumPy/SciPy: no case, no run, no study folder (a leaf module)."""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

LETTERS = "ABCDEFGHJKLMNOPQRSTUVWXYZ"  # factor letters, I skipped (the identity of the defining relation)

# The minimum-aberration generators of the 2^(k-p) fractions (Montgomery 2013, Table 8.14; Box, Hunter & Hunter
# 2005, Table 6.22), keyed by (k, p): factor letters of the generated factors in order. ``tests`` checks each
# one's resolution against the table's.
STANDARD_GENERATORS = {
    (3, 1): ("C = AB",),                                           # III, 4 runs
    (4, 1): ("D = ABC",),                                          # IV, 8 runs
    (5, 1): ("E = ABCD",),                                         # V, 16 runs
    (5, 2): ("D = AB", "E = AC"),                                  # III, 8 runs
    (6, 1): ("F = ABCDE",),                                        # VI, 32 runs
    (6, 2): ("E = ABC", "F = BCD"),                                # IV, 16 runs
    (6, 3): ("D = AB", "E = AC", "F = BC"),                        # III, 8 runs
    (7, 1): ("G = ABCDEF",),                                       # VII, 64 runs
    (7, 2): ("F = ABCD", "G = ABDE"),                              # IV, 32 runs
    (7, 3): ("E = ABC", "F = BCD", "G = ACD"),                     # IV, 16 runs
    (7, 4): ("D = AB", "E = AC", "F = BC", "G = ABC"),             # III, 8 runs
    (8, 2): ("G = ABCD", "H = ABEF"),                              # V, 64 runs
    (8, 3): ("F = ABC", "G = ABD", "H = BCDE"),                    # IV, 32 runs
    (8, 4): ("E = BCD", "F = ACD", "G = ABC", "H = ABD"),          # IV, 16 runs
    (9, 3): ("G = ABCD", "H = ACEF", "J = CDEF"),                  # IV, 64 runs
    (9, 4): ("F = BCDE", "G = ACDE", "H = ABDE", "J = ABCE"),      # IV, 32 runs
    (9, 5): ("E = ABC", "F = BCD", "G = ACD", "H = ABD", "J = ABCD"),  # III, 16 runs
    (10, 4): ("G = BCDF", "H = ACDF", "J = ABDE", "K = ABCE"),     # IV, 64 runs
    (10, 5): ("F = ABCD", "G = ABCE", "H = ABDE", "J = ACDE", "K = BCDE"),  # IV, 32 runs
    (10, 6): ("E = ABC", "F = BCD", "G = ACD", "H = ABD", "J = ABCD", "K = AB"),  # III, 16 runs
    (11, 5): ("G = CDE", "H = ABCD", "J = ABF", "K = BDEF", "L = ADEF"),  # IV, 64 runs
    (11, 6): ("F = ABC", "G = BCD", "H = CDE", "J = ACD", "K = ADE", "L = BDE"),  # IV, 32 runs
    (11, 7): ("E = ABC", "F = BCD", "G = ACD", "H = ABD", "J = ABCD", "K = AB", "L = AC"),  # III, 16 runs
}
ROMAN = {1: "I", 2: "II", 3: "III", 4: "IV", 5: "V", 6: "VI", 7: "VII", 8: "VIII", 9: "IX", 10: "X", 11: "XI"}


class DesignError(ValueError):
    """A design that cannot be built: the message says what is wrong and what is allowed."""


@dataclass(frozen=True)
class TwoLevelDesign:
    """A 2^(k-p) design: ``letters`` of its k factors, ``generators`` (``"E = ABC"``), the ``words`` of its
    defining relation (each a frozenset of letters), ``resolution`` (None for a full factorial: no word),
    ``matrix`` (runs x k, coded -1/+1, standard order of the base factors)."""

    letters: tuple
    generators: tuple
    words: tuple
    resolution: int | None
    matrix: np.ndarray
    folded: tuple = ()  # the letters a fold-over reversed in its second half of the runs (``fold_over``)

    @property
    def runs(self) -> int:
        return self.matrix.shape[0]

    def label(self) -> str:
        k = len(self.letters)
        p = k - int(round(math.log2(self.runs)))
        kind = f"2^{k}" if p == 0 else f"2^({k}-{p})"
        fold = "" if not self.folded else (" (a fold-over on all factors)" if len(self.folded) == k
                                            else f" (a fold-over on {word_text(self.folded)})")
        return f"{kind}, {self.runs} runs{fold}, " + (
            "full factorial" if self.resolution is None
            else f"resolution {ROMAN.get(self.resolution, self.resolution)}")

    def defining_relation(self) -> str:
        return "I" + "".join(f" = {word_text(w)}" for w in self.words) if self.words else "I (full factorial)"

    def aliases(self, effect, up_to: int = 3) -> list:
        """The effects aliased with ``effect`` (a string of letters, e.g. ``"AB"``), of order <= ``up_to``,
        shortest first."""
        e = frozenset(effect)
        found = sorted({word_text(e ^ w) for w in self.words if len(e ^ w) <= up_to}, key=lambda s: (len(s), s))
        return found

    def column(self, effect) -> np.ndarray:
        """The coded column of ``effect`` (letters): the product of its factors' columns."""
        col = np.ones(self.runs)
        for letter in effect:
            col = col * self.matrix[:, self.letters.index(letter)]
        return col

    def alias_classes(self) -> list:
        """Every estimable contrast of the design (2^(k-p) - 1 of them), as its alias chain: a list of effects
        (letter strings) that share one column, shortest and earliest first."""
        classes, seen = [], set()
        for order in range(1, len(self.letters) + 1):
            for combo in itertools.combinations(self.letters, order):
                effect = frozenset(combo)
                if effect in seen:
                    continue
                chain = {effect} | {effect ^ w for w in self.words}
                seen |= chain
                if frozenset() in chain:  # a word of the defining relation: aliased with the mean
                    continue
                classes.append(sorted((word_text(c) for c in chain if c), key=lambda s: (len(s), s)))
        return classes


def word_text(word) -> str:
    return "".join(sorted(word, key=LETTERS.index))


def parse_generator(text: str, letters: tuple, names: dict | None = None) -> tuple[str, frozenset]:
    """``"E = ABC"`` (letters) or ``"e = a*b*c"`` (factor names, ``names``: name -> letter) as
    ``(generated letter, base letters)``; ``DesignError`` saying what is allowed."""
    names = names or {}
    if not isinstance(text, str) or text.count("=") != 1:
        raise DesignError(f"{text!r}: a generator is 'E = ABC' (factor letters) or 'name = name*name*name'")
    left, right = (s.strip() for s in text.split("="))

    def letter_of(token):
        if token in names:
            return names[token]
        if token in letters:
            return token
        raise DesignError(f"{text!r}: {token!r} is neither a factor's letter ({''.join(letters)}) nor its name "
                          f"({', '.join(names) or 'none'})")

    generated = letter_of(left)
    tokens = [t.strip() for t in right.split("*")] if "*" in right or right in names else list(right)
    base = [letter_of(t) for t in tokens if t]
    if not base or len(set(base)) != len(base):
        raise DesignError(f"{text!r}: the right-hand side names two or more distinct factors, each once")
    if generated in base:
        raise DesignError(f"{text!r}: a factor cannot generate itself")
    return generated, frozenset(base)


def two_level(k: int, generators=(), *, names: dict | None = None, fraction: int | None = None) -> TwoLevelDesign:
    """The 2^(k-p) design of ``k`` factors. ``generators``: ``"E = ABC"`` strings, one per generated factor (the
    last p letters, each generated once from the k - p base factors); or ``fraction = p`` for the standard
    minimum-aberration generators (``STANDARD_GENERATORS``); neither: the full factorial."""
    if not isinstance(k, int) or not 2 <= k <= len(LETTERS):
        raise DesignError(f"{k!r} factors: a two-level design has 2 to {len(LETTERS)} factors")
    letters = tuple(LETTERS[:k])
    if fraction:
        if generators:
            raise DesignError("give either generators or fraction, not both")
        if (k, fraction) not in STANDARD_GENERATORS:
            known = ", ".join(f"{p}" for kk, p in sorted(STANDARD_GENERATORS) if kk == k) or "none"
            raise DesignError(f"fraction = {fraction} with {k} factors: no standard 2^({k}-{fraction}) design; for {k} "
                              f"factors fraction may be {known}, or give the generators")
        generators = STANDARD_GENERATORS[(k, fraction)]
    parsed = [parse_generator(g, letters, names) for g in generators]
    p = len(parsed)
    base_letters = letters[:k - p]
    generated = [g for g, _ in parsed]
    if sorted(generated) != sorted(letters[k - p:]):
        raise DesignError(f"generators {list(generators)}: with {k} factors and {p} generators they must generate "
                          f"the last {p} factors ({', '.join(letters[k - p:])}), each once")
    for text, (g, base) in zip(generators, parsed):
        if not base <= set(base_letters):
            raise DesignError(f"{text!r}: a generator is a product of base factors ({''.join(base_letters)})")
    n = 2 ** (k - p)
    matrix = np.empty((n, k))
    for j in range(k - p):  # standard order: the first factor alternates fastest
        matrix[:, j] = np.where((np.arange(n) // 2 ** j) % 2 == 0, -1.0, 1.0)
    for g, base in parsed:
        col = np.ones(n)
        for b in base:
            col *= matrix[:, letters.index(b)]
        matrix[:, letters.index(g)] = col
    generator_words = [base | {g} for g, base in parsed]
    words = set()
    for r in range(1, p + 1):
        for combo in itertools.combinations(generator_words, r):
            w = frozenset()
            for x in combo:
                w = w ^ x
            words.add(w)
    words = tuple(sorted(words, key=lambda w: (len(w), word_text(w))))
    if any(len(w) < 3 for w in words):
        short = word_text(min(words, key=len))
        raise DesignError(f"generators {list(generators)}: the defining relation holds the word {short}, so two "
                          "main effects (or a main effect and the mean) share a column; choose other generators")
    if len({tuple(r) for r in matrix}) != n:
        raise DesignError(f"generators {list(generators)}: runs repeat")
    resolution = min(len(w) for w in words) if words else None
    return TwoLevelDesign(letters, tuple(f"{g} = {word_text(b)}" for g, b in parsed), words, resolution, matrix)



def fold_over(design: TwoLevelDesign, letters) -> TwoLevelDesign:
    """``design`` with its fold-over on ``letters`` (Montgomery 2013, §8.6.2; Box, Hunter & Hunter 2005, §6.9): a
    second half of runs, the first's with the signs of those factors reversed. The combined design's defining
    relation keeps the words that hold an even number of the folded letters (the others change sign between the
    halves and leave the relation). Folded on one factor, every two-factor interaction with it comes clear of the
    others; folded on all, a resolution-III design becomes resolution IV. The halves are not treated as blocks: a
    simulated run has no day-to-day drift (its replicas differ by their beds only)."""
    folded = frozenset(letters)
    if not folded or not folded <= set(design.letters):
        raise DesignError(f"fold-over on {sorted(folded)}: one or more of the design's factors "
                          f"({''.join(design.letters)})")
    if design.folded:
        raise DesignError("the design is folded over already: a second fold-over is a design of its own")
    words = tuple(w for w in design.words if len(w & folded) % 2 == 0)
    if len(words) == len(design.words):
        raise DesignError(f"a fold-over on {word_text(folded)} repeats the design's own runs (every word of its "
                          f"defining relation holds an even number of them): fold over other factors")
    second = design.matrix.copy()
    for letter in folded:
        second[:, design.letters.index(letter)] *= -1.0
    resolution = min(len(w) for w in words) if words else None
    return TwoLevelDesign(design.letters, design.generators, words, resolution, np.vstack([design.matrix, second]),
                          tuple(sorted(folded, key=LETTERS.index)))

# --------------------------------------------------------------------------- analysis of a response
@dataclass(frozen=True)
class Effect:
    """One estimated effect: ``term`` (letters, e.g. ``"A"`` or ``"AB"``), ``aliases`` (its chain, up to
    three-factor interactions), ``estimate`` (mean at +1 less mean at -1), ``se`` (its standard error, None
    without an error estimate), ``low`` / ``high`` (the confidence interval), ``t`` (estimate / se)."""

    term: str
    aliases: tuple
    estimate: float
    se: float | None
    low: float | None
    high: float | None

    @property
    def t(self) -> float | None:
        return None if not self.se else self.estimate / self.se

    def decided(self) -> bool:
        """Whether the interval excludes zero (the effect is told from nothing at the chosen confidence)."""
        return self.low is not None and (self.low > 0 or self.high < 0)


@dataclass(frozen=True)
class Analysis:
    effects: tuple  # Effect per main effect, then per resolvable two-factor interaction chain
    error: str  # where the interval comes from: "pure error", "residual", "Lenth's PSE" or "none"
    error_df: float
    sigma: float | None  # the run-to-run standard deviation the error term gives (None for Lenth's)
    mean: float
    runs: int
    confidence: float


def model_terms(design: TwoLevelDesign) -> list:
    """The terms an analysis estimates: every main effect, then one term per alias chain of two-factor
    interactions that holds no main effect (named by its first two-factor interaction; its chain says what it
    also holds)."""
    terms = [(letter, tuple(design.aliases(letter))) for letter in design.letters]
    for chain in design.alias_classes():
        if any(len(e) == 1 for e in chain):
            continue
        twos = [e for e in chain if len(e) == 2]
        if twos:
            terms.append((twos[0], tuple(e for e in chain if e != twos[0] and len(e) <= 3)))
    return terms


def analyse(design: TwoLevelDesign, coded: np.ndarray, y: np.ndarray, *, confidence: float = 0.95,
            centre: np.ndarray | None = None) -> Analysis:
    """The effects of a response ``y`` over runs whose coded factor levels are the rows of ``coded`` (the
    design's rows, repeated for replicas, in any order; a missing run may be left out), by least squares on
    the mean, the main effects and the resolvable two-factor-interaction chains (``model_terms``).
    ``centre``: responses of centre-point runs (all factors at 0), which add pure-error degrees of freedom
    (and do not enter the effects).

    The error term, in order of preference: pure error, from runs repeated at the same point and from the
    centre points (pooled within-point variance); else the residual of the fit (the design's unused contrasts
    and missing-run imbalance); else, for a saturated unreplicated design, Lenth's pseudo standard error
    (Lenth 1989, *Technometrics* 31:469; PSE = 1.5 median(|c_j| : |c_j| < 2.5 s0), s0 = 1.5 median |c_j|, with
    d = m/3 degrees of freedom for m contrasts). Intervals: estimate +- t(1 - (1 - confidence)/2, df) se."""
    from scipy import stats
    coded, y = np.asarray(coded, float), np.asarray(y, float)
    terms = model_terms(design)
    columns = [np.ones(len(y))]
    for term, _ in terms:
        col = np.ones(len(y))
        for letter in term:
            col = col * coded[:, design.letters.index(letter)]
        columns.append(col)
    X = np.column_stack(columns)
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    rank = np.linalg.matrix_rank(X)
    residual = y - X @ coef
    n = len(y)
    # pure error: the spread of runs at the same point (replicas), and of the centre points
    groups = {}
    for row, value in zip(map(tuple, coded), y):
        groups.setdefault(row, []).append(value)
    pure_ss = sum(float(np.sum((np.array(v) - np.mean(v)) ** 2)) for v in groups.values())
    pure_df = sum(len(v) - 1 for v in groups.values())
    if centre is not None and len(centre) > 1:
        c = np.asarray(centre, float)
        pure_ss += float(np.sum((c - c.mean()) ** 2))
        pure_df += len(c) - 1
    xtx_inv = np.linalg.pinv(X.T @ X)
    scale = np.sqrt(np.diag(xtx_inv))[1:]  # se(coef) / sigma
    if pure_df > 0:
        error, df, sigma = "pure error", float(pure_df), math.sqrt(pure_ss / pure_df)
    elif n - rank > 0:
        error, df, sigma = "residual", float(n - rank), math.sqrt(float(residual @ residual) / (n - rank))
    else:
        error, df, sigma = "none", 0.0, None
    estimates = 2.0 * coef[1:]
    # below the response's rounding an effect is none (a deterministic response: exactly equal runs)
    estimates[np.abs(estimates) < 1e-9 * max(1.0, float(np.max(np.abs(y))))] = 0.0
    if sigma is not None:
        ses = 2.0 * sigma * scale
    elif len(estimates) >= 3:  # a saturated, unreplicated design: Lenth's pseudo standard error
        error = "Lenth's PSE"
        # over every contrast of the design (a balanced design: all effects share one standard error)
        contrasts = np.abs(estimates)
        s0 = 1.5 * float(np.median(contrasts))
        trimmed = contrasts[contrasts < 2.5 * s0]
        pse = 1.5 * float(np.median(trimmed)) if len(trimmed) else s0
        df = len(contrasts) / 3.0
        ses = np.full(len(estimates), pse)
    else:
        ses = None
    q = stats.t.ppf(1 - (1 - confidence) / 2, df) if df > 0 and ses is not None else None
    effects = []
    for j, (term, chain) in enumerate(terms):
        se = None if ses is None else float(ses[j])
        low, high = (None, None) if q is None or se is None else (estimates[j] - q * se, estimates[j] + q * se)
        effects.append(Effect(term, chain, float(estimates[j]), se, None if low is None else float(low),
                              None if high is None else float(high)))
    return Analysis(tuple(effects), error, df, sigma, float(coef[0]), n, confidence)
