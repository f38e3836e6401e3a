MODULE MainModule
    ! Pick from the camera-located tray, place into five nests, glue the fixture.
    PROC main()
        ConfJ\On;
        ConfL\On;
        MoveAbsJ jHome\NoEOffs, v1000, z50, tGripper;
        Pick;
        FOR i FROM 1 TO 5 DO
            MoveAbsJ jt_pPlace_offs{i}, v1000, z20, tGripper\WObj:=wTable;
            MoveAbsJ jt_pPlace{i}, v200, fine, tGripper\WObj:=wTable;
            MoveAbsJ jt_pPlace_offs{i}, v1000, z20, tGripper\WObj:=wTable;
        ENDFOR
        MoveExtJ jTurn, vrot50, fine;
        Glue;
        MoveAbsJ jPark, v1000, z50, tGripper;
        MoveAbsJ jHome, v1000, fine, tGripper;
    ENDPROC

    PROC Pick()
        ! The camera measured the tray: shift the program by pdTray.
        PDispSet pdTray;
        MoveJ pPickApp, v1000, z50, tGripper\WObj:=wTable;
        MoveL pPick, v200, fine, tGripper\WObj:=wTable;
        MoveL pPickApp, v500, z50, tGripper\WObj:=wTable;
        PDispOff;
    ENDPROC

    PROC Glue()
        MoveAbsJ jt_pGlue{1}, v500, z10, tGlue\WObj:=wFixture;
        FOR k FROM 2 TO 8 DO
            MoveAbsJ jt_pGlue{k}, v100, z1, tGlue\WObj:=wFixture;
        ENDFOR
    ENDPROC
ENDMODULE
