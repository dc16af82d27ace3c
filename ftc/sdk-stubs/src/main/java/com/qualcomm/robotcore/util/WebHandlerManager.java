// motorlab stub of the FTC SDK API (written from its public signatures; no SDK code). Compile-time only:
// on a robot the real SDK class is used. See docs/ftc-robot.md.
package com.qualcomm.robotcore.util;

import org.firstinspires.ftc.robotcore.internal.webserver.WebHandler;

/** The robot controller web server's handler registry: exact URIs ("command") to handlers. */
public interface WebHandlerManager {
    void register(String command, WebHandler webHandler);

    WebHandler getRegistered(String command);
}
