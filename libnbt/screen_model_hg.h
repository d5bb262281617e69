/* written by doc/screenmodel.sh from nbt-fit screenmodel: see doc/screenspace.md */
"# placeholder\n"
