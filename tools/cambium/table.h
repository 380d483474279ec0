/* A table of numbers read from a CSV file or from the array of objects of a JSON file, for
 * `cambium plot`: named columns of doubles, NaN where a cell is empty or not a number. */
#ifndef CBM_CLI_TABLE_H
#define CBM_CLI_TABLE_H

#include <stdbool.h>
#include <stddef.h>

typedef struct cli_table {
    size_t ncols, nrows;
    char **names;  /* ncols */
    double **cols; /* ncols arrays of nrows */
} cli_table;

/// Reads path as CSV (a header line of names, then one row per line; lines starting with '#'
/// and empty lines are skipped; cells may be double-quoted) or, for a .json file, the first
/// array of objects in it (a column per member of the first object; numbers, null as NaN).
/// On failure returns false with a message "path:line: what" in err.
bool cli_table_read(const char *path, cli_table *t, char *err, size_t err_size);
/// The column named `name`, or numbered (1-based) when name is a number; -1 if none.
long cli_table_column(const cli_table *t, const char *name);
void cli_table_free(cli_table *t);

#endif
