"""
Domains of continuity and the sequential topological complexity TC_n.

The paper's algorithm has domains W_l = union of A_{j_1} x ... x A_{j_n} with
j_1 + ... + j_n = l (Section 4): l runs over n max(r, 1) .. n (k + r), that is
nk + 1 domains for r >= 1 and n(k - 1) + 1 for r = 0 (doc/design.md section 7).
"""


def domain_range(configuration_count: int, robot_count: int,
                 obstacle_count: int) -> tuple[int, int]:
    """Return the smallest and largest domain value l = sum of cp(C_m)."""
    n, k, r = configuration_count, robot_count, obstacle_count
    return n * max(r, 1), n * (k + r)


def sequential_complexity(configuration_count: int, robot_count: int, obstacle_count: int,
                          dimension: int) -> int:
    """
    Return TC_n(F(R^d - Q_r, k)), non-reduced (paper, Theorem 1.1, González–Grant).

    n(k-1)+1 for r = 0, d odd; n(k-1) for r = 0, d even; nk for r = 1, d even;
    nk + 1 otherwise. The theorem assumes k >= 2; for k = 1 the space is R^d
    minus r points (contractible, a sphere S^{d-1} or a wedge of them), whose
    TC_n is 1, n + (d odd) and n + 1, which the same table gives except for
    r = 0 with d even: returned as 1 there.
    """
    n, k, r, d = configuration_count, robot_count, obstacle_count, dimension
    if r == 0:
        if k == 1:
            return 1
        return n * (k - 1) + 1 if d % 2 else n * (k - 1)
    if r == 1 and d % 2 == 0:
        return n * k
    return n * k + 1
