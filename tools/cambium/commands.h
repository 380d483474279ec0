/* The command table: one line per subcommand, X(name, function, summary). Each function lives
 * in its own file cmd_<name>.c. */
#ifndef CBM_COMMANDS_H
#define CBM_COMMANDS_H

int cmd_info(int argc, char **argv);

#define CBM_COMMANDS(X) X("info", cmd_info, "what a model or output file holds")

#endif
