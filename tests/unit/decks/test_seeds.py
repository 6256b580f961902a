"""The primality test and the insertion seeds LIGGGHTS takes (vibrofeed.geometry): at the
boundaries where trial division goes wrong (squares of primes, products of two primes on
either side of the square root, the largest seed LIGGGHTS takes), and for all inputs."""

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vibrofeed.geometry import _is_prime, insertion_seeds

LIMIT = 200_000
SIEVE = [True] * (LIMIT + 1)
SIEVE[0] = SIEVE[1] = False
for _n in range(2, math.isqrt(LIMIT) + 1):
    if SIEVE[_n]:
        SIEVE[_n * _n::_n] = [False] * len(SIEVE[_n * _n::_n])
PRIMES = [n for n, p in enumerate(SIEVE) if p]


@pytest.mark.parametrize("n, prime", [
    (-7, False), (0, False), (1, False), (2, True), (3, True), (4, False),
    (9, False), (25, False), (49, False), (121, False), (169, False),  # squares of primes
    (10007 ** 2, False), (46337 ** 2, False),  # the last square below 2**31 of a prime
    (10007 * 10009, False), (99991 * 100003, False),  # one factor each side of the root
    (561, False), (41041, False),  # Carmichael numbers: no Fermat test in disguise
    (2 ** 31 - 1, True), (2 ** 31 - 3, False), (10007, True), (2 ** 16 + 1, True),
])
def test_primality_at_its_boundaries(n, prime):
    assert _is_prime(n) is prime


@settings(max_examples=400, deadline=None)
@given(st.integers(min_value=-5, max_value=LIMIT))
def test_primality_is_the_sieves(n):
    assert _is_prime(n) is (n >= 0 and SIEVE[n])


@settings(max_examples=200, deadline=None)
@given(st.sampled_from(PRIMES[1:200]), st.sampled_from(PRIMES[1:200]))
def test_a_product_of_two_primes_is_no_prime(p, q):
    assert not _is_prime(p * q)


@settings(max_examples=100, deadline=None)
@given(st.integers(min_value=0, max_value=10 ** 12), st.integers(min_value=1, max_value=12))
def test_insertion_seeds_are_distinct_primes_in_liggghts_range_for_any_seed(seed, count):
    seeds = insertion_seeds(seed, count)
    assert len(seeds) == count == len(set(seeds))
    assert all(10_000 < p < 2 ** 31 and _is_prime(p) for p in seeds)
    assert seeds == sorted(seeds) and insertion_seeds(seed, count) == seeds  # deterministic
    assert insertion_seeds(seed, count + 1)[:count] == seeds  # more seeds extend, not reshuffle


def test_the_largest_seeds_stay_below_two_to_the_31():
    seeds = insertion_seeds(LIMIT - 1, 6)  # the highest base the mapping reaches
    assert max(seeds) < 2 ** 31
    # seeds differing by a multiple of 200 000 share their primes: the mapping is periodic
    assert insertion_seeds(5489, 6) == insertion_seeds(5489 + LIMIT, 6)
    assert insertion_seeds(5489, 6) != insertion_seeds(5490, 6)
