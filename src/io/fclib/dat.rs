//! Siconos' `.dat` text files (2-D and 3-D; the format in the parent's module doc):
//! tokens read and counted against the file before anything is allocated.

use super::*;

/// Parses the text of a `.dat` problem; `path` names the file in errors.
pub fn parse_dat(path: &Path, text: &str) -> Result<FrictionContactProblem, Error> {
    let mut tok = text.split_whitespace().enumerate();
    let file = path.display().to_string();
    let mut next = |what: &str| -> Result<&str, Error> {
        tok.next().map(|(_, t)| t).ok_or_else(|| {
            Error::invalid(&file, "end of file", &format!("truncated: expected {what}"))
        })
    };
    let int = |t: &str, what: &str| -> Result<usize, Error> {
        t.parse::<usize>().map_err(|_| {
            Error::invalid(
                &format!("{}: {what}", path.display()),
                t,
                "expected a non-negative integer",
            )
        })
    };
    let real = |t: &str, what: &str| -> Result<f64, Error> {
        t.parse::<f64>().map_err(|_| {
            Error::invalid(
                &format!("{}: {what}", path.display()),
                t,
                "expected a number",
            )
        })
    };
    let dim = int(next("the dimension")?, "dimension")?;
    if !(dim == 2 || dim == 3) {
        return Err(Error::invalid(
            &format!("{}: dimension", path.display()),
            dim,
            "expected 2 or 3 (spacedim)",
        ));
    }
    let nc = int(next("the contact count")?, "contact count")?;
    let storage = int(next("the matrix storage type")?, "storage type")?;
    if storage > 1 {
        return Err(Error::invalid(
            &format!("{}: storage type", path.display()),
            storage,
            "only dense (0) and sparse-block (1) matrices are read (2, CSparse's print, \
             rounds the values to 6 digits)",
        ));
    }
    let s0 = int(next("the matrix rows")?, "matrix rows")?;
    let s1 = int(next("the matrix columns")?, "matrix columns")?;
    let n = nc.saturating_mul(dim);
    let size_err = |got: String| {
        Error::invalid(
            &format!("{}: matrix size", path.display()),
            got,
            &format!("expected {n}×{n} for {nc} contacts in dimension {dim}"),
        )
    };
    if s0 != n || s1 != n {
        return Err(size_err(format!("{s0}×{s1}")));
    }
    // dense: every value needs at least two bytes (digit and separator); sparse-block:
    // q and μ must be in the file, and the dense copy of W may not exceed 100 bytes
    // of W per byte of file (64 MiB at least)
    let dense_needed = if storage == 0 { n.saturating_mul(n) } else { 0 };
    let needed = dense_needed.saturating_add(n).saturating_add(nc);
    let dense_bytes = (n as u64).saturating_mul(n as u64).saturating_mul(8);
    if n > MAX_ROWS
        || needed.saturating_mul(2) as u64 > text.len() as u64
        || (storage == 1 && dense_bytes > (100 * text.len() as u64).max(64 << 20))
    {
        return Err(Error::invalid(
            &format!("{}: contact count", path.display()),
            nc,
            &format!(
                "needs {needed} values and a {n}×{n} dense W, more than the file holds (or \
                 than {MAX_ROWS} dense rows)"
            ),
        ));
    }
    let mut w = vec![0.0; n * n];
    if storage == 0 {
        let r0 = int(next("the matrix rows (repeated)")?, "matrix rows")?;
        let r1 = int(next("the matrix columns (repeated)")?, "matrix columns")?;
        if r0 != n || r1 != n {
            return Err(size_err(format!("{s0}×{s1} ({r0}×{r1})")));
        }
        for (k, x) in w.iter_mut().enumerate() {
            *x = real(next("W values")?, &format!("W value {k}"))?;
        }
    } else {
        // Siconos' SparseBlockStructuredMatrix as SBM_write_in_file prints it: block
        // count, block rows and columns, cumulative block sizes of each, the compressed
        // block-row pointers and block-column indices, then each block's number and its
        // values column by column
        let at = |what: &str| format!("{}: sparse-block {what}", path.display());
        let bad = |what: &str, got: String, want: String| Error::invalid(&at(what), got, &want);
        let nblocks = int(next("the block count")?, "block count")?;
        if nblocks > 0 {
            let nbr = int(next("the block-row count")?, "block-row count")?;
            let nbc = int(next("the block-column count")?, "block-column count")?;
            if nbr == 0 || nbr > n || nbc == 0 || nbc > n {
                return Err(bad(
                    "block rows and columns",
                    format!("{nbr}, {nbc}"),
                    format!("expected 1..={n} each"),
                ));
            }
            let mut sizes = [Vec::new(), Vec::new()];
            for (side, count) in [(0, nbr), (1, nbc)] {
                let mut prev = 0;
                for b in 0..count {
                    let end = int(next("block sizes")?, "block size")?;
                    if end <= prev || end > n || end - prev > 3 {
                        return Err(bad(
                            "block sizes",
                            format!("{end} after {prev}"),
                            format!("cumulative ends rising by 1 to 3 up to {n}"),
                        ));
                    }
                    sizes[side].push(end);
                    prev = end;
                    if b + 1 == count && end != n {
                        return Err(bad("block sizes", end.to_string(), format!("last = {n}")));
                    }
                }
            }
            let filled1 = int(next("filled1")?, "filled1")?;
            let filled2 = int(next("filled2")?, "filled2")?;
            if filled1 != nbr + 1 || filled2 != nblocks || nblocks > nbr.saturating_mul(nbc) {
                return Err(bad(
                    "counts",
                    format!("filled1 {filled1}, filled2 {filled2}, {nblocks} blocks"),
                    format!("filled1 = {} and filled2 = the block count", nbr + 1),
                ));
            }
            let mut rowptr = Vec::with_capacity(filled1);
            for _ in 0..filled1 {
                let p = int(next("block-row pointers")?, "block-row pointer")?;
                if p > nblocks || rowptr.last().is_some_and(|&l| p < l) {
                    return Err(bad(
                        "block-row pointers",
                        p.to_string(),
                        format!("non-decreasing up to {nblocks}"),
                    ));
                }
                rowptr.push(p);
            }
            if rowptr[0] != 0 || rowptr[nbr] != nblocks {
                return Err(bad(
                    "block-row pointers",
                    format!("{}..{}", rowptr[0], rowptr[nbr]),
                    format!("0..{nblocks}"),
                ));
            }
            let mut colidx = Vec::with_capacity(filled2);
            for _ in 0..filled2 {
                let c = int(next("block-column indices")?, "block-column index")?;
                if c >= nbc {
                    return Err(bad(
                        "block-column indices",
                        c.to_string(),
                        format!("< {nbc}"),
                    ));
                }
                colidx.push(c);
            }
            for br in 0..nbr {
                let (r0, r1) = (if br == 0 { 0 } else { sizes[0][br - 1] }, sizes[0][br]);
                for blk in rowptr[br]..rowptr[br + 1] {
                    let num = int(next("a block number")?, "block number")?;
                    if num != blk {
                        return Err(bad(
                            "block number",
                            num.to_string(),
                            format!("{blk} (blocks in order)"),
                        ));
                    }
                    let bc = colidx[blk];
                    let (c0, c1) = (if bc == 0 { 0 } else { sizes[1][bc - 1] }, sizes[1][bc]);
                    for c in c0..c1 {
                        for row in r0..r1 {
                            w[row + c * n] =
                                real(next("block values")?, &format!("block {blk} value"))?;
                        }
                    }
                }
            }
        }
    }
    let mut q = vec![0.0; n];
    for (k, x) in q.iter_mut().enumerate() {
        *x = real(next("q values")?, &format!("q value {k}"))?;
    }
    let mut mu = vec![0.0; nc];
    for (k, x) in mu.iter_mut().enumerate() {
        *x = real(next("μ values")?, &format!("mu value {k}"))?;
    }
    // older Siconos writers end the file with one flag, 0 or 1
    // (FrictionContactProblem00394.dat, Rover4609.dat, FC3D_Example1.dat): allowed once
    let mut rest = tok.peekable();
    if rest.peek().is_some_and(|(_, t)| *t == "0" || *t == "1") {
        rest.next();
    }
    if let Some((i, t)) = rest.next() {
        return Err(Error::invalid(
            &format!("{}: token {}", path.display(), i + 1),
            t,
            "is past the end of the problem (after the μ values and an optional 0/1 flag): \
             expected end of file",
        ));
    }
    FrictionContactProblem {
        dim,
        w,
        q,
        mu,
        guess: None,
        form: "dat",
        asymmetry: 0.0,
    }
    .finish(path)
}
